"""A browser opens the calibration page on a real `calibrate run` output: the confusion
matrix, F0.5 with its interval, and the per-core shares, hovered for their counts."""

from __future__ import annotations

import pytest

from tests.integration.web.conftest import save_screenshot


@pytest.fixture(scope="module")
def calibration_dir(tmp_path_factory):
    from transfertwin.cli import main

    out = tmp_path_factory.mktemp("cal") / "cal-run"
    assert main(["calibrate", "run", "--limit", "6", "--runs", "2", "--workers", "1",
                 "--out", str(out)]) == 0  # fmt: skip
    return out


@pytest.mark.slow
def test_browser_shows_the_calibration_and_hover_values(calibration_dir, console_factory, page,
                                                        tmp_path):  # fmt: skip
    console = console_factory("--calibration", str(calibration_dir))
    page.goto(console.url)
    page.wait_for_selector("#tab-calibration:not([hidden])")
    page.wait_for_selector("#cal-figures")
    figures = page.inner_text("#cal-figures")
    assert "F0.5" in figures and "95 % CI [" in figures and "bootstrap" in figures
    page.wait_for_selector("#cal-confusion .heatmaplayer")
    bars = page.locator("#cal-shares .barlayer .point path")
    bars.first.wait_for()
    assert bars.count() == 2  # o1: real and twin
    box = bars.first.bounding_box()
    page.mouse.move(box["x"] + box["width"] / 2, box["y"] + box["height"] / 2 + 2)
    hover = page.locator("#cal-shares .hoverlayer .hovertext")
    hover.first.wait_for()
    text = hover.first.text_content()
    assert "o1 real" in text and "of 6" in text and "95 % CI" in text
    save_screenshot(page, tmp_path, "web-console-calibration")
