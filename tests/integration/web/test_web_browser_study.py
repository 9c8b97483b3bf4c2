"""A browser opens the console on a study store: progress, the polar success map, hover."""

from __future__ import annotations

import pytest

from tests.integration.web.conftest import save_screenshot


@pytest.mark.slow
def test_browser_shows_the_polar_map_and_hover_values(tiny_study, console_factory, page,
                                                       tmp_path):  # fmt: skip
    console = console_factory("--db", str(tiny_study))
    page.goto(console.url)
    page.wait_for_selector("#study-tiny\\.sqlite")
    assert page.inner_text("#study-tiny\\.sqlite td.done") == "6 / 12"
    points = page.locator("#polar .scatterlayer path.point")
    points.first.wait_for()
    n_points = points.count()
    assert n_points == 6  # one marker per state run so far
    angles = page.eval_on_selector_all(
        "#polar .angularaxistick text", "els => els.map((e) => e.textContent)"
    )
    assert "-150°" in angles and "210°" not in angles  # θ signed, -179..180 (issue 30.4)
    box = points.first.bounding_box()
    page.mouse.move(box["x"] + box["width"] / 2, box["y"] + box["height"] / 2)
    hover = page.locator(".hoverlayer .hovertext")
    hover.first.wait_for()
    text = hover.first.text_content()  # SVG: no innerText
    assert "o1" in text and "θ =" in text and "success" in text
    page.wait_for_selector("#bw-o1 td.best")
    assert "front / both / θ = " in page.inner_text("#bw-o1 td.best")
    assert "n = 1" in page.inner_text("#bw-o1")
    assert page.inner_text("#bw-o1 td.advice").startswith("Put it")  # what to do, in words
    page.wait_for_selector("#ci-plot .scatterlayer path.point")
    assert page.locator("#ci-plot .scatterlayer path.point").count() == 6  # one per state
    best = page.locator("#bestworst-plot .scatterlayer path.point").first
    best.wait_for()
    box = best.bounding_box()
    page.mouse.move(box["x"] + box["width"] / 2, box["y"] + box["height"] / 2)
    bw_hover = page.locator("#bestworst-plot .hoverlayer .hovertext")
    bw_hover.first.wait_for()
    text = bw_hover.first.text_content()
    assert "o1 best" in text and "success 1 of 1" in text and "95 % CI" in text
    save_screenshot(page, tmp_path, "web-console-study")
    href = page.get_attribute("#study-tiny\\.sqlite a:text('CSV')", "href")
    assert href == "/api/studies/tiny.sqlite/results.csv"
