"""The console against a CPS started by the test (`transfertwin cps up`): assets from the
knowledge graph, AAS browsing and live values over OPC UA, orders followed to their outcome,
and no OPC UA credential in anything the browser receives. Browser tests drive Debian's
chromium through Playwright (marked slow)."""

from __future__ import annotations

import json
import subprocess
import sys
import time

import pytest
from starlette.testclient import TestClient

from tests.integration.web.conftest import credential_strings, save_screenshot, wait_for
from transfertwin.web import WebConfig, create_app

OUTCOMES = {"delivered", "failed at pick-up", "failed at delivery"}


def test_assets_live_values_orders_and_no_credentials(cps_workdir):
    cfg = WebConfig(cps=cps_workdir)
    seen: list[str] = []
    with TestClient(create_app(cfg), base_url="http://127.0.0.1",
                    raise_server_exceptions=False) as c:  # fmt: skip

        def get(path, **kw):
            res = c.get(path, **kw)
            seen.append(res.text + json.dumps(dict(res.headers)))
            return res

        def post(path, **kw):
            res = c.post(path, **kw)
            seen.append(res.text + json.dumps(dict(res.headers)))
            return res

        def ready():
            a = get("/api/assets").json()["assets"]
            return a if all(x["reachable"] and x["status"] == "online" for x in a) else None

        assets = {a["id"]: a for a in wait_for(ready, 120, "every asset online")}
        info = json.loads((cps_workdir / "cps.json").read_text())
        assert set(assets) == {a["id"] for a in info["assets"]}
        assert assets["TU_A"]["type"] == "D/E" and assets["TU_A"]["station"] == "A"
        assert "Transport" in assets["TM_1"]["capabilities"]
        assert assets["TMS"]["kind"] == "LogicalAsset"
        assert all(a["endpoint"].startswith("opc.tcp://127.") for a in assets.values())

        for aid in assets:
            sms = {s["id_short"]: s for s in get(f"/api/assets/{aid}/aas").json()["submodels"]}
            assert "Identification" in sms
        tu = {s["id_short"]: s for s in get("/api/assets/TU_A/aas").json()["submodels"]}
        props = {e["id_short"]: e for e in tu["OperationalData"]["elements"]}
        assert props["BeltSpeedLeft"]["value"] == 0.0
        assert get("/api/assets/NOPE/aas").status_code == 404
        assert get("/api/assets/..%2Fx/aas").status_code == 404

        t0 = time.monotonic()
        live = get("/api/live?max_events=4")
        elapsed = time.monotonic() - t0
        events = [json.loads(line[6:]) for line in live.text.splitlines()
                  if line.startswith("data: ")]  # fmt: skip
        assert len(events) == 4 and elapsed < 4.0  # >= 1 Hz
        assert events[-1]["online"]["TM_1"] and "State" in events[-1]["values"]["TM_1"]
        assert get("/api/live?max_events=x").status_code == 422

        auth = {"Authorization": f"Bearer {cfg.session_token}"}
        order = {"object": "o3", "source": "TU_C", "target": "TU_D"}  # o3 starts on TU_C
        assert post("/api/orders", json=order).status_code == 401
        assert post("/api/orders", json=order, headers={"Authorization": "Bearer x"}
                    ).status_code == 401  # fmt: skip
        bad = [
            ({**order, "object": "o99"}, 422),
            ({**order, "object": ["o3"]}, 422),
            ({**order, "target": "TU_C"}, 422),  # source == target
            ({**order, "target": "TU_Z"}, 422),
            ({**order, "target": "'; DROP"}, 422),
            ({**order, "speed": 3}, 422),
        ]
        for body, status in bad:
            res = post("/api/orders", json=body, headers=auth)
            assert res.status_code == status and res.json()["error"], (body, res.text)
        res = post("/api/orders", content=b"{not json", headers={**auth,
                   "Content-Type": "application/json"})  # fmt: skip
        assert res.status_code == 400
        res = post("/api/orders", content=b"[1, 2]", headers={**auth,
                   "Content-Type": "application/json"})  # fmt: skip
        assert res.status_code == 400
        res = post("/api/orders", content=b"object=o3", headers={**auth,
                   "Content-Type": "text/plain"})  # fmt: skip
        assert res.status_code == 415

        form = "object=o3&source=TU_C&target=D&token=" + cfg.session_token  # station D
        placed = post("/api/orders", content=form.encode(),
                      headers={"Content-Type": "application/x-www-form-urlencoded"})  # fmt: skip
        assert placed.status_code == 201, placed.text
        oid = placed.json()["id"]
        assert placed.json()["target"] == "TU_D"

        def finished():
            o = get(f"/api/orders/{oid}").json()
            return o if o["state"] == "finished" else None

        done = wait_for(finished, 300, "the order's outcome", period=1.0)
        assert done["outcome"].split(" (")[0] in OUTCOMES  # with the failed step's reason
        texts = [s["text"] for s in done["steps"]]
        assert any("docking at TU_C" in t for t in texts), texts  # the TMS's history
        assert get("/api/orders").json()["orders"][0]["id"] == oid

    secrets = credential_strings(cps_workdir)
    assert len(secrets) == 4
    for text in seen:
        for secret in secrets:
            assert secret not in text


@pytest.mark.slow
def test_browser_sees_assets_and_places_an_order(cps_workdir, console_factory, page, tmp_path):
    from playwright.sync_api import expect

    console = console_factory("--cps", str(cps_workdir))
    page.goto(console.url)
    page.wait_for_selector("#asset-TM_1 td.c-reachable.on", timeout=120_000)
    expect(page.locator("#assets td.c-reachable.on")).to_have_count(14, timeout=120_000)
    assert "token" not in page.url  # the token left the address bar
    live = page.inner_text("#asset-TU_A .c-live")
    assert "BeltSpeedLeft: " in live and "Json" not in live
    page.click("#asset-TU_A")
    page.wait_for_selector("#aas details[data-submodel='OperationalData']")
    save_screenshot(page, tmp_path, "web-console-assets")

    page.click("nav .tab[data-tab='orders']")
    page.select_option("#order-object", "o2")
    page.select_option("#order-source", "TU_B")  # o2 starts on TU_B
    page.select_option("#order-target", "TU_C")
    page.click("#order-submit")
    page.wait_for_selector("#order-message.ok")
    page.wait_for_selector("#orders tr[data-state='finished']", timeout=300_000)
    outcome = page.inner_text("#orders tr[data-state='finished'] td.outcome")
    assert outcome.split(" (")[0] in OUTCOMES
    save_screenshot(page, tmp_path, "web-console-order")
    html = page.content()
    for secret in credential_strings(cps_workdir):
        assert secret not in html
    console.stop()
    audit = (cps_workdir / "web-audit.log").read_text()
    assert "o2 TU_B -> TU_C" in audit


def _cps_up(wd) -> subprocess.Popen:
    up = subprocess.Popen(
        [sys.executable, "-m", "transfertwin", "cps", "up", "--single-process",
         "--policy", "nearest-idle", "--workdir",
         str(wd),
         "--time-scale", "0"], stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True,
    )  # fmt: skip
    line = up.stdout.readline()
    assert line.startswith("CPS up"), line
    return up


@pytest.mark.slow
def test_item8_1_a_cps_restarted_in_the_same_folder_is_followed(tmp_path):
    """The console keeps no old ports: stopped, every asset says why; started again in the
    same folder (new ports), it reads the new cps.json and every asset is online again."""
    from tests.integration.cps._cli import tt
    from tests.integration.web.conftest import _stop

    wd = tmp_path / "wd"
    up = _cps_up(wd)
    try:
        with TestClient(create_app(WebConfig(cps=wd)), base_url="http://127.0.0.1") as c:

            def assets():
                return {a["id"]: a for a in c.get("/api/assets").json()["assets"]}

            def all_online():
                a = assets()
                return a if all(x["reachable"] and x["status"] == "online"
                                for x in a.values()) else None  # fmt: skip

            def cli_order(obj: str, source: str, target: str) -> dict:
                done = tt("cps", "order", "--workdir", str(wd), "--object", obj, "--from",
                          source, "--to", target, timeout=200)  # fmt: skip
                assert done.returncode in (0, 3), done.stdout + done.stderr  # 3: failed there
                op = done.stdout.strip().splitlines()[-1].split()[0]

                def ended() -> dict | None:  # the console reads the TMS's ledger each second
                    rows = {r["operation"]: r for r in c.get("/api/orders").json()["orders"]}
                    row = rows.get(op)
                    return row if row is not None and row["state"] == "finished" else None

                return wait_for(ended, 30, f"{op} finished in the Orders tab")

            before = wait_for(all_online, 120, "every asset online")
            first = cli_order("o3", "TU_C", "TU_D")  # from the command line: in the Orders tab
            assert first["placed_by"] == "cps" and first["operation"] == "op1"
            assert first["object"] == "o3" and first["state"] == "finished"
            _stop(up)
            stopped = f"the CPS is not running (no cps.json in {wd}); start it with " \
                      "'transfertwin cps up'"  # fmt: skip
            down = wait_for(lambda: (a := assets()) and {x["reason"] for x in a.values()} == {
                            stopped} and a, 90, "every asset offline")  # fmt: skip
            assert not any(x["reachable"] for x in down.values())
            assert {x["status"] for x in down.values()} == {"unknown"}  # no old 'online'
            up = _cps_up(wd)
            after = wait_for(all_online, 120, "every asset online after the restart")
            info = json.loads((wd / "cps.json").read_text())
            assert {a["id"]: a["endpoint"] for a in info["assets"]} == {
                aid: a["endpoint"] for aid, a in after.items()}  # fmt: skip
            assert after["TU_A"]["endpoint"] != before["TU_A"]["endpoint"]
            live = c.get("/api/live?max_events=1").text
            event = json.loads(next(ln[6:] for ln in live.splitlines() if ln.startswith("data: ")))
            assert all(event["online"].values()) and not event["stale"]
            assert event["kg_error"] is None
            # the restarted floor goes on where it was: its TMS numbers on, each operation
            # is listed once with its own history
            again = cli_order("o2", "TU_B", "TU_A")
            assert again["operation"] == "op2" and again["object"] == "o2"
            assert not any("o3" in s["text"] for s in again["steps"]), again["steps"]
            rows = c.get("/api/orders").json()["orders"]
            assert [r["operation"] for r in rows] == ["op1", "op2"]
            assert rows[0]["object"] == "o3" and rows[0]["state"] == "finished"
    finally:
        _stop(up)
