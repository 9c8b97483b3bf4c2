"""The running floor in 3-D (issue 31, item 2) in Debian's chromium (WebGL via SwiftShader):
the page draws the floor file's stations and modules, follows the console's live feed, and
shows a transport module moving when an order is placed. Marked slow: a floor takes ~40 s to
start here."""

from __future__ import annotations

import io

import httpx
import numpy as np
import pytest
from starlette.testclient import TestClient

from tests.integration.cps._cli import tt, two_module_floor
from tests.integration.web.test_web_browser_replay import GL_ARGS
from transfertwin.web import WebConfig, create_app

pytestmark = pytest.mark.slow

READY = "() => { const f = window.__floor; return Boolean(f && (f.ready || f.error)); }"


@pytest.fixture(scope="module")
def floor(tmp_path_factory):
    """`cps up --floor F --detach --time-scale 1` (modules drive in real time); down at the end."""
    base = tmp_path_factory.mktemp("floor3d")
    (base / "floor.toml").write_text(two_module_floor("floor-3d", {"o1": "TU_A"}))
    wd = base / "w"
    up = tt("cps", "up", "--policy", "nearest-idle",
            "--floor", str(base / "floor.toml"), "--workdir", str(wd), "--detach",
            "--time-scale", "1", "--lease", "2", "--start-timeout", "150", timeout=200)
    try:
        assert up.returncode == 0, up.stdout + up.stderr
        yield wd
    finally:
        down = tt("cps", "down", "--workdir", str(wd))
        assert down.returncode == 0, down.stdout + down.stderr


def test_the_layout_comes_from_the_floor_file(floor):
    with TestClient(create_app(WebConfig(cps=floor)), base_url="http://127.0.0.1") as c:
        layout = c.get("/api/floor").json()
    assert [s["unit"] for s in layout["stations"]] == ["TU_A", "TU_B"]
    assert [m["id"] for m in layout["modules"]] == ["TM_1", "TM_2"]
    assert layout["objects"] == [{"id": "o1", "unit": "TU_A"}] and layout["size_m"] == [12, 8]


def test_the_3d_floor_shows_a_module_moving(floor, console_factory, chromium_path):
    from PIL import Image
    from playwright.sync_api import sync_playwright

    console = console_factory("--cps", str(floor))
    with sync_playwright() as p:
        browser = p.chromium.launch(executable_path=chromium_path, args=GL_ARGS)
        page = browser.new_page(viewport={"width": 1280, "height": 800})
        page.set_default_timeout(120_000)
        page.goto(console.url)
        assert page.get_attribute("#floor3d-link", "href") == "/floor3d"
        page.goto(console.base + "/floor3d")
        page.wait_for_function(READY)
        assert page.evaluate("window.__floor.error") is None
        page.wait_for_function("() => window.__floor.updates >= 2")
        before = np.asarray(Image.open(io.BytesIO(page.locator("#scene").screenshot())))
        assert len(np.unique(before.reshape(-1, before.shape[-1]), axis=0)) > 100
        placed = httpx.post(console.base + "/api/orders", json={"object": "o1", "target": "TU_B"},
                            headers={"Authorization": f"Bearer {console.token}"})  # fmt: skip
        assert placed.status_code == 201, placed.text
        page.wait_for_function(
            "() => Object.values(window.__floor.moved).some((d) => d > 0.3)", timeout=150_000)
        state = page.evaluate("({moved: window.__floor.moved, modules: window.__floor.modules})")
        after = np.asarray(Image.open(io.BytesIO(page.locator("#scene").screenshot())))
        assert (np.abs(after.astype(int) - before.astype(int)).sum(axis=2) > 30).mean() > 0.0005
        assert max(state["moved"].values()) > 0.3, state
        browser.close()
