"""Operations that use the twin on a floor of asset processes (docs/architecture.md,
"Operation"): orders by destination and by destination group, the auction, the object
loaded in the study store's best state (or the Experiment Manager's, predicted on the fly
for an object the store lacks), chained orders, refusals up front, the queue and the KPIs."""

from __future__ import annotations

import json
import time
from pathlib import Path

import pytest

from tests.integration.cps._cli import call_tms, run_main, small_study, tt, two_module_floor

#: A floor of 8 processes and a dozen orders (~100 s): slow, run by .ci/run on its own.
pytestmark = pytest.mark.slow

# stations A and B, two modules (both running), o1 on TU_A and o2 on TU_B; a third station C
# across the floor, the Experiment Manager, and the predictive policy
FLOOR = two_module_floor("operations", {"o1": "TU_A", "o2": "TU_B"}).replace(
    "standby = true", "standby = false").replace('logical = ["KG", "TMS"]',
                                                 'logical = ["KG", "TMS", "EM"]') + """
[[station]]
name = "C"
x_m = 10.0
y_m = 1.4
yaw_deg = -90.0
mount = "left"

[operation]
policy = "predictive"
study = "study.sqlite"
runs = 1
capacity = 1

[operation.groups]
out = ["TU_B", "TU_C"]
"""


@pytest.fixture(scope="module")
def floor(tmp_path_factory):
    base = tmp_path_factory.mktemp("operations")
    (base / "floor.toml").write_text(FLOOR)
    small_study(base / "study.sqlite", "o1")  # 12 states, one run each
    wd = base / "w"
    up = tt("cps", "up", "--floor", str(base / "floor.toml"), "--workdir", str(wd), "--detach",
            "--time-scale", "0", "--start-timeout", "150", timeout=200)
    assert up.returncode == 0, up.stderr
    try:
        yield wd
    finally:
        down = tt("cps", "down", "--workdir", str(wd))
    assert down.returncode == 0, down.stdout + down.stderr


def _wait_finished(wd: Path, op_id: str, timeout_s: float = 120) -> dict:
    t0 = time.monotonic()
    while time.monotonic() - t0 < timeout_s:
        status = json.loads(call_tms(wd, "OperationStatus", op_id))
        if status["state"] == "finished":
            return status
        time.sleep(0.3)
    raise AssertionError(f"{op_id} did not finish in {timeout_s} s")


def test_an_order_by_destination_group_is_auctioned_and_loaded_in_the_twins_best_state(
        floor, capfd):  # fmt: skip
    from transfertwin.cps.dispatch._predict import study_predictions

    res = run_main(capfd, "cps", "order", "--workdir", str(floor), "--object", "o1",
                   "--to", "out")  # fmt: skip
    assert res.returncode in (0, 3), res.stderr  # 3: delivered or not, it ended
    assert "submitted op1: o1 TU_A -> out" in res.stdout
    status = json.loads(call_tms(floor, "OperationStatus", "op1"))
    auction = status["auction"]
    assert set(auction["bids"]) == {"TM_1", "TM_2"}  # both idle modules bid
    assert set(auction["bids"]["TM_1"]) == {"TU_C"}  # TU_B holds o2: no candidate
    best = study_predictions(floor.parent / "study.sqlite", "o1")[0]
    assert status["plan"]["state"] == best.state
    assert status["plan"]["prediction"]["share"] == best.share
    # the winner is the lowest expected time per successful delivery (p = 0: time alone)
    costs = {(m, u): eta / (best.share or 1.0) for m, b in auction["bids"].items()
             for u, eta in b.items()}  # fmt: skip
    assert (auction["winner"], auction["target"]) == min(costs, key=costs.get)
    assert status["result"]["loaded_state"] == best.state
    assert status["result"]["floor_s"] > 0
    orders = json.loads(run_main(capfd, "cps", "orders", "--workdir", str(floor),
                                 "--json").stdout)  # fmt: skip
    assert orders[0]["state"] in ("done", "failed") and orders[0]["loaded_state"] == best.state


def test_orders_for_one_object_chain_and_what_cannot_start_is_refused(floor, capfd):
    ledger = json.loads(call_tms(floor, "Ledger"))
    if "o1" in ledger["unknown"]:  # lost in the gap by the first test: an operator finds it
        free = "TU_A" if not [o for o, at in ledger["locations"].items() if at == "TU_A"] else (
            "TU_C")  # fmt: skip
        assert run_main(capfd, "cps", "locate", "--workdir", str(floor), "--object", "o1",
                        "--at", free).returncode == 0  # fmt: skip
    where = json.loads(call_tms(floor, "Ledger"))["locations"]["o1"]
    first = call_tms(floor, "OrderTo", "o1", "TU_A" if where != "TU_A" else "TU_C")
    second = call_tms(floor, "OrderTo", "o1", "out")  # while the first runs: it waits
    queued = json.loads(call_tms(floor, "OperationStatus", second))
    assert queued["after"] == first and queued["source"] is None
    a, b = _wait_finished(floor, first), _wait_finished(floor, second)
    assert b["source"] == a["location"] or b["result"]["status"] != "delivered"
    assert any(f"{first} ended" in what for _, what in b["history"])
    # refused up front, one line, exit 2: an occupied unit, an unknown destination
    at = json.loads(call_tms(floor, "Ledger"))["locations"]["o1"]
    if at.startswith("TU_"):
        occupied = run_main(capfd, "cps", "order", "--workdir", str(floor), "--object", "o2",
                            "--to", at)  # fmt: skip
        assert occupied.returncode == 2 and "the destination is occupied" in occupied.stderr
        assert len(occupied.stderr.strip().splitlines()) == 1
    nowhere = run_main(capfd, "cps", "order", "--workdir", str(floor), "--object", "o1",
                       "--to", "TU_Z")  # fmt: skip
    assert nowhere.returncode == 2 and "destination groups: out" in nowhere.stderr


def test_an_object_the_store_lacks_is_predicted_by_the_experiment_manager(floor):
    ledger = json.loads(call_tms(floor, "Ledger"))
    assert "o2" not in ledger["unknown"]
    held = set(ledger["locations"].values())  # capacity 1: to a unit that holds nothing
    free = next(u for u in ("TU_A", "TU_C") if u not in held)
    # 28 states run by the EM first (a minute on a quiet machine, minutes on a loaded one)
    status = _wait_finished(floor, call_tms(floor, "OrderTo", "o2", free), timeout_s=900)
    plan = status["plan"]
    assert "prediction" in plan, status["history"]
    # adaptive (the default) with one run a state: its first round is the whole budget
    assert plan["prediction"]["source"] == "adaptive virtual experiments (28 runs, at most 28)"
    assert plan["prediction"]["n"] == 1 and plan["next_best"] is not None
    assert any("asking the Experiment Manager" in what for _, what in status["history"])
    if status["result"].get("loaded_state") is not None:  # it was loaded: in that state
        assert status["result"]["loaded_state"] == plan["state"]


def test_kpis_count_every_order(floor, capfd):
    k = json.loads(run_main(capfd, "cps", "kpis", "--workdir", str(floor), "--json").stdout)
    orders = json.loads(call_tms(floor, "Orders"))
    finished = [o for o in orders if o["state"] in ("done", "failed")]
    assert k["policy"] == "predictive" and k["orders"] == len(orders)
    assert k["delivered"] == sum(o["state"] == "done" for o in orders)
    assert k["finished"] == len(finished) >= 3
    low, high = k["success_share_ci95"]
    assert low <= k["success_share"] <= high
    assert set(k["utilisation"]["modules"]) == {"TM_1", "TM_2"}
    assert set(k["utilisation"]["units"]) == {"TU_A", "TU_B", "TU_C"}
    text = run_main(capfd, "cps", "kpis", "--workdir", str(floor))
    assert text.returncode == 0 and "success share" in text.stdout
