"""What the 3-D floor and the console draw of what the feed says, in Debian's chromium with a
scripted feed (no floor to start): an object the ledger has lost is drawn nowhere and listed
as unknown, an offline module is drawn offline, a moving module leaves a path (without
three.js's 'Buffer size too small' warning), live JSON values read as fields, the favicon is
served. Marked slow (a browser)."""

from __future__ import annotations

import json

import httpx
import pytest

from tests.integration.web.test_web_browser_replay import GL_ARGS

pytestmark = pytest.mark.slow

LAYOUT = {
    "name": "scripted", "size_m": [12, 8],
    "stations": [{"name": "A", "unit": "TU_A", "x_m": 2.0, "y_m": 2.0, "yaw_deg": 0.0,
                  "mount": "fixed"},
                 {"name": "B", "unit": "TU_B", "x_m": 9.0, "y_m": 6.0, "yaw_deg": 180.0,
                  "mount": "fixed"}],
    "modules": [{"id": "TM_1", "x_m": 4.0, "y_m": 4.0, "theta_deg": 0.0, "standby": False},
                {"id": "TM_2", "x_m": 6.0, "y_m": 1.0, "theta_deg": 90.0, "standby": False}],
    "objects": [{"id": "o1", "unit": "TU_A"}, {"id": "o2", "unit": "TU_B"}],
}  # fmt: skip


def _event(i: int) -> str:
    data = {
        "online": {"TU_A": True, "TU_B": True, "TM_1": True, "TM_2": False},
        "values": {"TM_1": {"PoseX": 4.0 + 0.5 * i, "PoseY": 4.0, "PoseTheta": 0.0},
                   "TM_2": {"PoseX": 6.0, "PoseY": 1.0, "PoseTheta": 1.5708},
                   "o1": {"PossessedBy": ""}, "o2": {"PossessedBy": "TU_B"}},
        "orders": [],
    }  # fmt: skip
    return f"event: live\ndata: {json.dumps(data)}\n\n"


def test_the_3d_floor_draws_unknown_offline_and_a_path(console_factory, chromium_path):
    from playwright.sync_api import sync_playwright

    console = console_factory()
    assert httpx.get(console.base + "/favicon.ico").headers["content-type"].startswith("image/svg")
    with sync_playwright() as p:
        browser = p.chromium.launch(executable_path=chromium_path, args=GL_ARGS)
        page = browser.new_page(viewport={"width": 1280, "height": 800})
        page.set_default_timeout(60_000)
        messages: list[str] = []
        page.on("console", lambda m: messages.append(m.text))
        page.route("**/api/floor*", lambda r: r.fulfill(json=LAYOUT))
        body = "".join(_event(i) for i in range(6))
        page.route("**/api/live*", lambda r: r.fulfill(
            status=200, body=body, headers={"Content-Type": "text/event-stream"}))  # fmt: skip
        page.goto(console.base + "/floor3d")
        page.wait_for_function("() => window.__floor && window.__floor.updates >= 6")
        page.wait_for_function("() => window.__floor.renders >= 3")
        state = page.evaluate(
            "({o: window.__floor.objects, off: window.__floor.offline, "
            "trails: window.__floor.trails, error: window.__floor.error})"
        )
        assert state["error"] is None
        assert state["o"] == {"o1": "unknown", "o2": "TU_B"}
        assert state["off"]["TM_2"] is True and state["off"]["TM_1"] is False
        assert state["trails"]["TM_1"] == 6
        assert "o1: place unknown" in page.text_content("#objects")
        assert "TM_2 (6.00, 1.00) m offline" in page.text_content("#modules")
        assert not [m for m in messages if "Buffer size too small" in m], messages
        browser.close()


ASSETS = {
    "assets": [{"id": a, "class": c, "kind": "PhysicalAsset", "type": None, "capabilities": [],
                "station": None, "status": "online", "state": "idle", "endpoint": "opc.tcp://x",
                "security": None, "reachable": True, "reason": None, "pid": None,
                "joined": False}
               for a, c in (("TU_A", "transfer_unit"), ("TU_B", "transfer_unit"),
                            ("TM_1", "transport_module"), ("o1", "object"))],
    "kg_error": None, "tms_error": None, "objects": ["o1"], "units": ["TU_A", "TU_B"],
    "groups": [],
}  # fmt: skip
CONFIG = {"cps": True, "studies": [], "calibrations": [], "reads_need_token": False,
          "live_period_s": 0.5}  # fmt: skip
POSES = json.dumps({"TM_1": {"x": 1.2, "y": 0.8, "theta": 0.0, "sd_x": 0.004}})
LIVE = {"online": {"TU_A": True, "TU_B": True, "TM_1": True, "o1": True}, "reason": {},
        "stale": [], "seen": {}, "kg_error": None, "kpis": None,
        "values": {"o1": {"PossessedBy": "TU_A"}, "TM_1": {"FusedPosesJson": POSES}},
        "display": {"o1": [["PossessedBy", "TU_A"]],
                    "TM_1": [["FusedPoses", "TM_1 at (1.20, 0.80) m ± 0.4 cm, θ 0°"]]},
        "orders": [{"id": "op1", "operation": "op1", "object": "o1", "source": "TU_B",
                    "target": "TU_A", "state": "finished", "outcome": "delivered",
                    "placed_by": "cps", "steps": [{"t": 1.7e9, "text": "assigned to TM_1 for "
                    "TU_A (expected 225 s of modelled floor time)"}]}]}  # fmt: skip


def _scripted_console(browser, live: dict):
    """A page whose console config, asset list and live feed (`live`, one event) are
    scripted; `goto` is the test's."""
    page = browser.new_page(viewport={"width": 1400, "height": 900})
    page.set_default_timeout(60_000)
    page.route("**/api/config*", lambda r: r.fulfill(json=CONFIG))
    page.route("**/api/assets", lambda r: r.fulfill(json=ASSETS))
    body = f"event: live\ndata: {json.dumps(live)}\n\n"
    page.route("**/api/live*", lambda r: r.fulfill(
        status=200, body=body, headers={"Content-Type": "text/event-stream"}))  # fmt: skip
    return page


def test_the_console_reads_values_as_fields_and_defaults_to_a_valid_order(
    console_factory, chromium_path
):
    from playwright.sync_api import sync_playwright

    console = console_factory()
    with sync_playwright() as p:
        browser = p.chromium.launch(executable_path=chromium_path, args=["--no-sandbox"])
        page = _scripted_console(browser, LIVE)
        page.route("**/api/assets/TM_1/aas", lambda r: r.fulfill(json={
            "submodels": [{"id_short": "OperationalData", "elements": [
                {"id_short": "PoseTheta", "kind": "property", "value": 3.14159,
                 "text": "180.0°"}]}], "read_utc": "2026-01-01T10:00:00+00:00"}))  # fmt: skip
        page.goto(console.base + "/")
        page.wait_for_function(
            "() => document.querySelector('#asset-TM_1 .c-live')"
            " && document.querySelector('#asset-TM_1 .c-live').textContent"
        )
        live = page.text_content("#asset-TM_1 .c-live")
        assert live == "FusedPoses: TM_1 at (1.20, 0.80) m ± 0.4 cm, θ 0°", live
        assert page.input_value("#order-object") == "o1"
        page.wait_for_function("() => document.querySelector('#order-target').value === 'TU_B'")
        page.click("#asset-TM_1")
        page.wait_for_function("() => document.querySelector('#aas-read').textContent")
        assert page.text_content("#aas-read").startswith("read over OPC UA at ")
        assert "180.0°" in page.text_content("#aas-body")
        assert "modelled floor time" in page.text_content("#orders thead")
        browser.close()


KPIS = {"policy": "predictive", "orders": 3, "finished": 3, "delivered": 1, "failed": 1,
        "faults": 1, "in_progress": 0, "operations_per_hour": 12.0, "success_share": 0.5,
        "success_share_ci95": [0.0126, 0.9874], "mean_lead_time_s": 30.0,
        "utilisation": {"modules": {"TM_1": 0.4}, "units": {"TU_A": 0.1}},
        "failed_by_reason": {"failed while transferring": 1},
        "faults_by_reason": {"TM_1 went offline (lease expired) while transferring": 1},
        }  # fmt: skip


def test_the_console_shows_a_fault_apart_from_the_failures(console_factory, chromium_path):
    """The KPI panel counts a module lost mid-operation as a fault with its reason, not as a
    failure (the panel said nothing of faults: only the TMS's JSON counted them)."""
    from playwright.sync_api import sync_playwright

    console = console_factory()
    with sync_playwright() as p:
        browser = p.chromium.launch(executable_path=chromium_path, args=["--no-sandbox"])
        page = _scripted_console(browser, {**LIVE, "kpis": KPIS})
        page.goto(console.base + "/")
        page.wait_for_function("() => !document.querySelector('#kpis').hidden")
        text = page.text_content("#kpis")
        assert "1 delivered, 1 failed, 1 faults, 0 in progress" in text, text
        assert ("faults (not in the share): TM_1 went offline (lease expired) while "
                "transferring: 1") in text, text
        assert "failed: failed while transferring: 1" in text, text
        browser.close()
