"""The 3-D replay labels what it shows (Debian's chromium, WebGL through SwiftShader): TM and
TU in the scene, an arrow for the direction the belts run, what happens and the outcome in
words over the view; at 1280×900 the info panel sits beside the canvas and never covers the
TM's far end or the object. Marked slow (a browser and a replay server)."""

from __future__ import annotations

import pytest

from tests.integration.web.conftest import save_screenshot
from tests.integration.web.test_web_browser_replay import READY, ReplayServer, _seek

pytestmark = pytest.mark.slow

ROUND_TRIP = ["--object", "o1", "--face", "front", "--conveyor", "left", "--theta", "90",
              "--seed", "3"]  # fmt: skip


def _inside(point, box) -> bool:
    x, y = point
    return box["x"] <= x <= box["x"] + box["width"] and box["y"] <= y <= box["y"] + box["height"]


def test_the_replay_labels_units_travel_and_outcome_and_the_panel_hides_nothing(
    chromium_path, tmp_path
):
    from playwright.sync_api import sync_playwright

    from tests.integration.web.test_web_browser_replay import GL_ARGS

    server = ReplayServer(*ROUND_TRIP)
    try:
        with sync_playwright() as p:
            browser = p.chromium.launch(executable_path=chromium_path, args=GL_ARGS)
            page = browser.new_page(viewport={"width": 1280, "height": 900})
            page.set_default_timeout(120_000)
            page.goto(server.url)
            page.wait_for_function(READY)
            assert page.evaluate("window.__replay.error") is None
            assert page.text_content("#result").startswith("delivered and brought back in")
            markers = page.evaluate("window.__replay.markers")
            crossing = (markers[1]["t"] + markers[2]["t"]) / 2  # between start and arrival
            _seek(page, crossing)
            now = page.evaluate("({travel: window.__replay.travel, text: window.__replay.caption})")
            assert now == {"travel": 1, "text": "crossing TM → TU"}
            assert page.text_content("#outcome") == "crossing TM → TU"
            hud = page.locator("#hud").bounding_box()
            canvas = page.locator("#scene").bounding_box()
            assert hud["x"] + hud["width"] <= canvas["x"], (hud, canvas)
            for what in ("window.__replay.tmEnd", "window.__replay.objectCentre"):
                x, y = page.evaluate(f"window.__replay.screenOf({what})")
                on_page = (canvas["x"] + x, canvas["y"] + y)
                assert _inside(on_page, canvas) and not _inside(on_page, hud), (what, on_page)
            for label in ("TM", "TU"):
                x, y = page.evaluate(f"window.__replay.labelAt('{label}')")
                assert 0 <= x <= canvas["width"] and 0 <= y <= canvas["height"], label
            save_screenshot(page, tmp_path, "replay-labels")
            _seek(page, page.evaluate("window.__replay.duration"))
            caption = page.text_content("#outcome")
            assert caption.startswith("delivered and brought back in"), caption
            browser.close()
    finally:
        server.stop()
