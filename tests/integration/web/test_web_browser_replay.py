"""The 3-D replay in Debian's chromium (Playwright; WebGL through SwiftShader): the canvas
draws and changes with time, scrubbing to the failure marker shows the object in the gap, the
controls work, and a 30 s transfer's replay loads in under 2 s (issue 31)."""

from __future__ import annotations

import io
import os
import subprocess
import sys

import numpy as np
import pytest

from tests.integration.web.conftest import _stop, save_screenshot

pytestmark = pytest.mark.slow

GL_ARGS = ["--no-sandbox", "--use-angle=swiftshader", "--enable-unsafe-swiftshader",
           "--ignore-gpu-blocklist"]  # fmt: skip
GAP = ["--object", "o1", "--face", "front", "--conveyor", "both", "--theta", "90", "--seed", "3",
       "--gap-mm", "80"]  # fmt: skip
READY = "() => { const r = window.__replay; return Boolean(r && (r.ready || r.error)); }"
#: What "loads" means: from navigation to the first rendered frame (the page's own clock).
#: The absolute figure (under 2 s for a 30 s replay) is a speed claim: it is measured in
#: benchmarks/replay_load.py, not asserted here (it took 11 s once on a busy host).


class ReplayServer:
    """`transfertwin replay ... --no-browser --port 0` in a subprocess."""

    def __init__(self, *args: str) -> None:
        self.proc = subprocess.Popen(
            [sys.executable, "-m", "transfertwin", "replay", "--no-browser", "--port", "0",
             *args], stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
        )  # fmt: skip
        self.summary = self.proc.stdout.readline()
        line = self.proc.stdout.readline()
        assert line.startswith("replay: http://"), self.summary + line
        self.url = line.split(" ", 1)[1].strip()

    def stop(self) -> str:
        return _stop(self.proc)


@pytest.fixture(scope="module")
def browser(chromium_path):
    from playwright.sync_api import sync_playwright

    with sync_playwright() as p:
        b = p.chromium.launch(executable_path=chromium_path, args=GL_ARGS)
        yield b
        b.close()


@pytest.fixture(scope="module")
def gap_server():
    server = ReplayServer(*GAP)
    yield server
    server.stop()


def _new_page(browser, height: int = 800):
    """A page in its own context; every wait of it (and of pages it opens) up to 2 min."""
    page = browser.new_page(viewport={"width": 1280, "height": height})
    page.context.set_default_timeout(120_000)
    page.context.set_default_navigation_timeout(120_000)
    return page


def _open(browser, url: str):
    page = _new_page(browser)
    errors: list[str] = []
    page.on("pageerror", lambda e: errors.append(str(e)))
    page.goto(url)
    page.wait_for_function(READY)
    assert page.evaluate("window.__replay.error") is None
    return page, errors


def _canvas(page) -> np.ndarray:
    from PIL import Image

    png = page.locator("#scene").screenshot()
    return np.asarray(Image.open(io.BytesIO(png)).convert("RGB")).astype(int)


def _seek(page, t: float) -> None:
    page.evaluate(f"window.__replay.seek({t})")
    n = page.evaluate("window.__replay.renders")
    page.wait_for_function("n => window.__replay.renders > n + 1", arg=n)  # drawn at the new time


def test_the_replay_draws_and_the_failure_marker_shows_the_object_in_the_gap(
    browser, gap_server, tmp_path
):
    page, errors = _open(browser, gap_server.url)
    state = page.evaluate("({d: window.__replay.duration, m: window.__replay.markers,"
                          " n: window.__replay.frames})")  # fmt: skip
    assert state["n"] > 30 and [m["kind"] for m in state["m"]] == ["none", "pre", "failure"]
    _seek(page, 0.0)
    start = _canvas(page)
    # Non-blank: many distinct colours, not one background.
    assert len(np.unique(start.reshape(-1, 3), axis=0)) > 200 and start.std() > 10
    assert not page.evaluate("window.__replay.inGap")
    # The object's centre at t = 0, and the pixel there, before anything moved.
    centre0 = page.evaluate("window.__replay.objectCentre")
    page.click(".marker.failure")
    page.wait_for_function("() => window.__replay.ots === '0'")
    n = page.evaluate("window.__replay.renders")
    page.wait_for_function("n => window.__replay.renders > n + 1", arg=n)
    failure = page.evaluate("""() => { const r = window.__replay;
        return {t: r.t, inGap: r.inGap, centre: r.objectCentre, ots: r.ots, gap: r.gap,
                px: r.screenOf(r.objectCentre), playing: r.playing}; }""")
    end_marker = state["m"][-1]["t"]
    assert failure["t"] == pytest.approx(end_marker) and not failure["playing"]
    assert failure["inGap"] and failure["ots"] == "0"
    assert failure["gap"]["tmTip"] < failure["centre"][0] < failure["gap"]["tuNearX"]
    assert failure["centre"][0] - centre0[0] > 0.1  # it travelled towards the TU
    at_failure = _canvas(page)
    save_screenshot(page, tmp_path, "replay-failure")
    changed = np.abs(at_failure - start).sum(axis=2) > 30
    assert changed.mean() > 0.002  # the picture changed between the two times
    # Pixels: the object is drawn where its centre projects (in the gap), and was not there
    # at t = 0 (where the gap's red or the belts showed).
    x, y = (round(v) for v in failure["px"])
    patch = at_failure[y - 3 : y + 4, x - 3 : x + 4].reshape(-1, 3).mean(axis=0)
    before = start[y - 3 : y + 4, x - 3 : x + 4].reshape(-1, 3).mean(axis=0)
    assert np.abs(patch - before).sum() > 40, (patch, before)
    assert patch[0] > patch[2] + 15, patch  # the core's bronze: more red than blue
    assert errors == []


def test_the_controls_play_scrub_speed_and_hulls(browser, gap_server):
    page, errors = _open(browser, gap_server.url)
    page.select_option("#speed", "4")
    page.click("#play")
    page.wait_for_function("() => window.__replay.t > 1.0")  # 4× speed: about 0.25 s of wall time
    page.wait_for_function("() => !window.__replay.playing")  # stops at the end
    assert page.evaluate("window.__replay.t") == pytest.approx(
        page.evaluate("window.__replay.duration"))  # fmt: skip
    page.evaluate("""() => { const s = document.getElementById('scrub');
        s.value = '0.5'; s.dispatchEvent(new Event('input')); }""")  # as a drag ends
    page.wait_for_function("() => Math.abs(window.__replay.t - 0.5) < 1e-6")
    plain = _canvas(page)
    page.check("#hulls")
    n = page.evaluate("window.__replay.renders")
    page.wait_for_function("n => window.__replay.renders > n + 1", arg=n)
    hulls = _canvas(page)
    assert (np.abs(hulls - plain).sum(axis=2) > 30).mean() > 0.0005
    assert errors == []


def _load(browser, url: str) -> tuple[float, float]:
    """(navigation-to-first-frame time in ms of a fresh page, the replay's length in s)."""
    page, errors = _open(browser, url)
    load_ms, duration = page.evaluate("[window.__replay.loadMs, window.__replay.duration]")
    assert errors == []
    page.close()
    return load_ms, duration


def test_a_30_s_transfer_replay_loads_about_as_fast_as_a_3_s_one(browser, gap_server, tmp_path):
    from transfertwin.sim import SceneConfig
    from transfertwin.study.experiment import save_profile

    profile = save_profile(tmp_path / "nostall.toml", "nostall",
                           SceneConfig().with_overrides(stall_time_s=None))  # fmt: skip
    server = ReplayServer("--object", "o1", "--face", "front", "--conveyor", "both", "--theta",
                          "0", "--seed", "3", "--profile", str(profile))  # fmt: skip
    long, short = [], []
    try:
        assert "caught in the gap after 30.03 s" in server.summary, server.summary
        for _ in range(5):  # interleaved, best of five each: the machine is shared
            long.append(_load(browser, server.url))
            short.append(_load(browser, gap_server.url))
    finally:
        server.stop()
    (long_ms, long_s), (short_ms, short_s) = min(long), min(short)
    load = os.getloadavg()[0] / (os.cpu_count() or 1)
    print(f"first frame after navigation, best of 5: {long_ms:.0f} ms for the {long_s:.2f} s "
          f"replay, {short_ms:.0f} ms for the {short_s:.2f} s one; load {load:.1f} per core")
    assert long_s > 30.0 and short_s < 5.0
    # The replay's length costs little: three.js, the WebGL context and the first frame
    # dominate (holds however busy the machine is).
    assert long_ms < 1.5 * short_ms + 500, (long_ms, short_ms)


def test_the_studies_page_links_each_state_to_its_replay(browser, tiny_study, console_factory):
    console = console_factory("--db", str(tiny_study))
    page = _new_page(browser, 900)
    page.goto(console.url)
    page.wait_for_selector("#bw-o1 a.replay-link")
    best = page.get_attribute("#bw-o1 a.replay-link", "href")
    assert best.startswith("/replay?study=tiny.sqlite&object=o1&face=") and best.endswith("run=0")
    # A click on a state in the success map opens that state's replay in a new page.
    point = page.locator("#polar .scatterlayer path.point").first
    point.wait_for()
    box = point.bounding_box()
    with page.context.expect_page() as opened:
        page.mouse.click(box["x"] + box["width"] / 2, box["y"] + box["height"] / 2)
    replay = opened.value
    replay.wait_for_function(READY)
    assert replay.evaluate("window.__replay.error") is None
    assert "/replay?study=tiny.sqlite&object=o1" in replay.url
    replay.wait_for_selector("#check")
    assert "same bits as the stored row of tiny.sqlite" in replay.inner_text("#check")


def test_the_calibration_page_links_each_row_to_its_replay(browser, console_factory, tmp_path):
    from transfertwin.cli import main

    out = tmp_path / "cal2"
    assert main(["calibrate", "run", "--limit", "2", "--runs", "1", "--workers", "1",
                 "--out", str(out)]) == 0  # fmt: skip
    console = console_factory("--calibration", str(out))
    page = _new_page(browser, 900)
    page.goto(console.url)
    page.click('nav .tab[data-tab="calibration"]')
    page.wait_for_selector("#cal-row-1 a.replay-link")
    href = page.get_attribute("#cal-row-1 a.replay-link", "href")
    assert href == "/replay?calibration=cal2&row=1&run=0"
    with page.context.expect_page() as opened:
        page.click("#cal-row-1 a.replay-link")
    replay = opened.value
    replay.wait_for_function(READY)
    assert replay.evaluate("window.__replay.error") is None
    assert "cal2 row 1" in replay.inner_text("#check") and "(agrees)" in replay.inner_text("#check")


def test_a_plant_experiment_replays_from_its_recording(browser, tmp_path):
    """A plant table's row (`replay --plant-rows`): the page draws the recording, the picture
    changes, and it says where the outcome comes from (the plant's log)."""
    import csv

    from transfertwin.plant import PLANT_COLUMNS, EmulatedPlant, PlantRequest

    rows = EmulatedPlant(918273).run([PlantRequest("o3", "back", "both", 45, "TU_B")])
    table = tmp_path / "plant_calibration.csv"
    with table.open("w", newline="") as fh:
        writer = csv.DictWriter(fh, PLANT_COLUMNS, lineterminator="\n")
        writer.writeheader()
        writer.writerows(rows)
    server = ReplayServer("--plant-rows", str(table), "--row", "0", "--plant-seed", "918273")
    try:
        page, errors = _open(browser, server.url)
        state = page.evaluate("({d: window.__replay.duration, m: window.__replay.markers})")
        assert [m["kind"] for m in state["m"]] == ["none", "pre", "success", "pre", "success"]
        _seek(page, 0.0)
        start, centre0 = _canvas(page), page.evaluate("window.__replay.objectCentre")
        assert len(np.unique(start.reshape(-1, 3), axis=0)) > 200 and start.std() > 10
        _seek(page, state["m"][2]["t"])  # the end of the transfer there: on the TU
        later, centre1 = _canvas(page), page.evaluate("window.__replay.objectCentre")
        assert centre1[0] - centre0[0] > 0.1  # it went over to the TU
        assert (np.abs(later - start).sum(axis=2) > 30).mean() > 0.002
        assert "the plant's log: success" in page.inner_text("#result")
        assert "recorded on the plant" in page.inner_text("#check")
        save_screenshot(page, tmp_path, "replay-plant")
        assert errors == []
    finally:
        server.stop()
