"""A browser starts a simulated transfer in the console and sees it move on the live
schematic: the object's footprint changes, a light barrier turns red, the outcome shows."""

from __future__ import annotations

import pytest

from tests.integration.web.conftest import save_screenshot


@pytest.mark.slow
def test_browser_sees_the_live_transfer_move(console_factory, page, tmp_path):
    console = console_factory()  # no CPS, no study: the console opens on the live view
    page.goto(console.url)
    page.wait_for_selector("#tab-live:not([hidden])")
    page.select_option("#tr-object", "o1")
    page.select_option("#tr-conveyor", "both")
    page.fill("#tr-theta", "90")
    page.fill("#tr-speed", "2")
    page.click("#transfer-submit")
    page.wait_for_selector("#transfer-message.ok")
    page.wait_for_selector("#schematic polygon#object[points]")
    first = page.get_attribute("#object", "points")
    page.wait_for_function(
        "p => document.getElementById('object').getAttribute('points') !== p", arg=first
    )
    page.wait_for_selector("#schematic line.barrier.interrupted", state="attached")
    save_screenshot(page, tmp_path, "web-console-live")
    page.wait_for_selector("#transfer-info[data-state='finished']", timeout=120_000)
    info = page.inner_text("#transfer-info")
    assert "finished" in info and "success" in info
    assert int(page.get_attribute("#schematic", "data-events")) >= 5
