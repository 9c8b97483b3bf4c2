"""What the console makes of a floor that changes (issue 27, item 8): a CPS restarted in the
same folder, assets that join and leave, stale values, and the Orders tab keyed by unique
operation ids whoever placed them. Pure functions and a gateway that is never started."""

from __future__ import annotations

import json
import os
import time
from pathlib import Path

from transfertwin.web._floor import (
    asset_condition,
    merge_assets,
    order_rows,
    read_floor_info,
)
from transfertwin.web._gateway import CpsGateway, Order

ASSETS = [
    {"id": "KG", "kind": "logical", "class": "knowledge_graph",
     "endpoint": "opc.tcp://127.0.0.2:4840/transfertwin/KG", "security_policy": "None"},
    {"id": "TU_A", "kind": "physical", "class": "transfer_unit",
     "endpoint": "opc.tcp://127.0.0.4:4841/transfertwin/TU_A", "security_policy": "None"},
    {"id": "o1", "kind": "physical", "class": "object",
     "endpoint": "opc.tcp://127.0.0.5:4842/transfertwin/o1", "security_policy": "None"},
]  # fmt: skip


def write_info(wd: Path, assets=ASSETS) -> None:
    wd.mkdir(parents=True, exist_ok=True)
    info = {"assets": assets, "credentials_file": None,
            "cert_dir": str(wd / "certs"), "insecure": True}  # fmt: skip
    (wd / "cps.json").write_text(json.dumps(info))


def test_item8_1_a_rewritten_cps_json_has_a_new_stamp_and_endpoints(tmp_path):
    write_info(tmp_path)
    first = read_floor_info(tmp_path)
    moved = [dict(a, endpoint=a["endpoint"].replace(":48", ":58")) for a in ASSETS]
    write_info(tmp_path, moved)
    os.utime(tmp_path / "cps.json", ns=(time.time_ns() + 10**9,) * 2)
    second = read_floor_info(tmp_path)
    assert first.stamp != second.stamp
    assert [a["endpoint"] for a in second.assets] == [a["endpoint"] for a in moved]
    (tmp_path / "cps.json").unlink()
    assert read_floor_info(tmp_path) is None  # a stopped CPS removes it
    (tmp_path / "cps.json").write_text('{"assets": [')  # being written
    assert read_floor_info(tmp_path) is None


def test_item3_an_asset_that_joined_at_runtime_is_watched_at_its_announced_address():
    status = [{"id": "TU_A", "online": True, "address": "opc.tcp://x"},
              {"id": "TM_2", "kind": "physical", "class": "transport_module", "online": True,
               "address": "opc.tcp://127.0.0.9:4850/transfertwin/TM_2"}]  # fmt: skip
    merged = merge_assets(ASSETS, status)
    assert list(merged) == ["KG", "TM_2", "TU_A", "o1"]
    assert merged["TM_2"]["endpoint"] == "opc.tcp://127.0.0.9:4850/transfertwin/TM_2"
    assert merged["TM_2"]["class"] == "transport_module" and merged["TM_2"]["joined"]
    assert merged["TU_A"]["endpoint"] == ASSETS[1]["endpoint"]  # cps.json's stays
    assert merge_assets(ASSETS, None) == {a["id"]: a for a in ASSETS}


def test_item8_1_offline_assets_say_why():
    assert asset_condition(True, None, {"online": True}) == (True, None)
    assert asset_condition(False, "ConnectionRefusedError", None) == (
        False, "not answering: nothing listens at its address (is the floor running?)")  # fmt: skip
    online, reason = asset_condition(False, "TimeoutError",
                                     {"online": False, "last_seen_s": 4.2})  # fmt: skip
    assert not online and reason == "left the floor (last heartbeat 4 s ago)"
    # the graph tells an announced leave from a lapsed lease, and since when
    left = {"online": False, "offline": {"reason": "left", "since_s": 12.4, "detail": "x"}}
    assert asset_condition(False, "X", left) == (False, "left the floor 12 s ago (announced)")
    lapsed = {
        "online": False,
        "offline": {
            "reason": "lapsed",
            "since_s": 3.0,
            "detail": "no heartbeat for 5 s (lease expired)",
        },
    }
    assert asset_condition(False, "X", lapsed) == (
        False, "lease lapsed 3 s ago (no heartbeat for 5 s (lease expired))")  # fmt: skip
    # up and idle (its lease held) is online while the console's session is reopened;
    # a module on standby is not 'not answering'
    assert asset_condition(False, "TimeoutError", {"online": True, "state": "idle"}) == (
        True, None)  # fmt: skip
    assert asset_condition(False, "ConnectionRefusedError", None, standby=True) == (
        False, "on standby (prepared, not started)")  # fmt: skip
    assert asset_condition(True, None, None, "the CPS is not running") == (
        False, "the CPS is not running")  # fmt: skip
    assert asset_condition(False, None, None) == (False, "connecting")


LEDGER = [
    {"operation": "op7", "object": "o1", "source": "TU_A", "target": "TU_B",
     "state": "finished", "phase": "done", "module": "TM_1", "submitted": 1.0,
     "history": [[1.0, "queued"], [2.0, "assigned to TM_1"], [9.0, "delivered"]],
     "result": {"status": "delivered"}},
    {"operation": "op8", "object": "o2", "source": "TU_B", "target": "TU_A",
     "state": "finished", "phase": "transfer", "module": "TM_2", "submitted": 10.0,
     "history": [[10.0, "queued"]],
     "result": {"status": "failed", "failed_step": "transfer", "reason": "TM_2 offline"}},
    {"operation": "op9", "object": "o1", "source": "TU_B", "target": "TU_A",
     "state": "running", "phase": "drive", "module": "TM_1", "submitted": 20.0,
     "history": [[20.0, "queued"], [21.0, "assigned to TM_1"]], "result": None},
]  # fmt: skip


def test_item8_3_orders_from_the_command_line_are_listed_with_the_consoles():
    placed = [{"id": "w1", "operation": "op9", "object": "o1", "source": "TU_B",
               "target": "TU_A", "state": "running", "outcome": None,
               "steps": [{"t": 19.5, "text": "submitted"}]}]  # fmt: skip
    rows = order_rows(LEDGER, placed)
    assert [r["operation"] for r in rows] == ["op7", "op8", "op9"]
    assert [r["placed_by"] for r in rows] == ["cps", "cps", "console"]
    assert rows[0]["outcome"] == "delivered" and rows[0]["id"] == "op7"
    assert rows[1]["outcome"] == "failed (transfer: TM_2 offline)"
    assert rows[2]["id"] == "w1"  # the console's id, the TMS's history
    assert [s["text"] for s in rows[2]["steps"]] == ["queued", "assigned to TM_1"]


def test_item8_2_each_operation_keeps_its_own_history():
    rows = order_rows(LEDGER, [])
    history = {r["operation"]: [s["text"] for s in r["steps"]] for r in rows}
    assert history == {"op7": ["queued", "assigned to TM_1", "delivered"],
                       "op8": ["queued"], "op9": ["queued", "assigned to TM_1"]}  # fmt: skip


def gateway(tmp_path: Path) -> CpsGateway:
    write_info(tmp_path)
    return CpsGateway(tmp_path)


def test_item8_4_a_graph_that_does_not_answer_shows_no_old_online_status(tmp_path):
    gw = gateway(tmp_path)
    gw.kg_rows = [{"id": a["id"], "status": "online", "state": "idle"} for a in ASSETS]
    gw.kg_error = "knowledge graph not answering (ConnectionRefusedError)"
    rows = {a["id"]: a for a in gw.assets()}
    assert {a["status"] for a in rows.values()} == {"unknown"}
    assert all(a["state"] is None for a in rows.values())


def test_item8_4_values_of_an_asset_that_stopped_answering_are_stale(tmp_path):
    gw = gateway(tmp_path)
    gw.values["TU_A"] = {"BarrierNearInterrupted": True}
    gw.online["TU_A"], gw.seen["TU_A"] = False, 100.0
    gw.errors["TU_A"] = "ConnectionRefusedError"
    gw.values["o1"], gw.online["o1"] = {"Face": "front"}, True
    gw.kg_status = {"TU_A": {"id": "TU_A", "online": False, "last_seen_s": 3.0},
                    "o1": {"id": "o1", "online": True}}  # fmt: skip
    live = gw.live()
    assert live["online"] == {"KG": False, "TU_A": False, "o1": True}
    assert live["stale"] == ["TU_A"] and live["seen"] == {"TU_A": 100.0}
    assert live["reason"]["TU_A"].startswith("left the floor (last heartbeat")
    assert "o1" not in live["reason"]
    rows = {a["id"]: a for a in gw.assets()}
    assert rows["TU_A"]["status"] == "offline" and not rows["TU_A"]["reachable"]
    assert rows["o1"]["status"] == "online"


def test_item8_1_a_stopped_cps_is_said_once_for_every_asset(tmp_path):
    gw = gateway(tmp_path)
    gw.online = dict.fromkeys(gw.online or ("KG", "TU_A", "o1"), True)
    gw.floor_error = "the CPS is not running (no cps.json)"
    live = gw.live()
    assert not any(live["online"].values())
    assert set(live["reason"].values()) == {"the CPS is not running (no cps.json)"}
    assert live["kg_error"] == gw.floor_error


def test_an_order_placed_here_is_shown_once_as_the_consoles_after_a_restart(tmp_path):
    """The console keeps its orders in the work folder: after the floor (or the console)
    restarted, an order placed here is one row, the console's, with the TMS's record (its
    state, steps and the source the TMS resolved), not a stuck copy beside a second row."""
    gw = gateway(tmp_path)
    order = Order("w1", "o1", "where it is", "TU_A", "2026-01-01T10:00:00+00:00", "127.0.0.1",
                  operation="op9", state="running")  # fmt: skip
    gw.orders[order.id] = order
    gw._keep_orders()
    again = gateway(tmp_path)  # a new console (or the same one after the floor restarted)
    assert list(again.orders) == ["w1"] and again._next_order() == 2
    again.ledger = LEDGER
    rows = again.order_rows()
    assert [r["operation"] for r in rows] == ["op7", "op8", "op9"]
    assert [r["placed_by"] for r in rows] == ["cps", "cps", "console"]
    mine = rows[2]
    assert mine["id"] == "w1" and mine["state"] == "running" and mine["source"] == "TU_B"
    assert [s["text"] for s in mine["steps"]] == ["queued", "assigned to TM_1"]
