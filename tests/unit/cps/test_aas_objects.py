"""What an object's AAS shows of its transfers, from the TMS's operation records (pure).

The records are written out here as the TMS keeps them (`OrderBook`), not made by it.
"""

from __future__ import annotations

import json
import math

from transfertwin.cps.aas import HISTORY_LIMIT, build_representation, demo_descriptors
from transfertwin.cps.aas import object_properties as shown

STATE = {"face": "back", "conveyor": "left", "theta_deg": -15}


def op(op_id: str, obj: str = "o2", *, submitted: float, state: str = "finished",
       status: str | None = "delivered", loaded: dict | None = None,
       plan: dict | None = STATE, steps: tuple = ()) -> dict:  # fmt: skip
    record = {"operation": op_id, "object": obj, "source": "TU_B", "target": "TU_D",
              "module": "TM_1", "state": state, "submitted": submitted,
              "steps": [list(s) for s in steps], "plan": {"state": plan}}  # fmt: skip
    if state == "finished":
        record["finished"] = submitted + 30.0
        record["result"] = {"status": status, "loaded_state": loaded}
    return record


def test_an_object_never_moved_shows_nothing() -> None:
    assert shown("o2", [op("op-1", "o3", submitted=1.0)]) == {
        "Face": "", "Conveyor": "", "Theta": 0.0, "LastTransfer": "", "TransferHistoryJson": "[]",
    }  # fmt: skip


def test_the_last_finished_transfer_gives_state_and_outcome() -> None:
    ops = [
        op("op-2", submitted=20.0, status="failed at pick-up",
           loaded={"face": "front", "conveyor": "both", "theta_deg": 90}),
        op("op-1", submitted=10.0),
    ]  # fmt: skip
    got = shown("o2", ops)
    assert (got["Face"], got["Conveyor"]) == ("front", "both")  # the module's, not the plan's
    assert got["Theta"] == math.pi / 2
    assert got["LastTransfer"] == "failed at pick-up"
    history = json.loads(got["TransferHistoryJson"])
    assert [h["operation"] for h in history] == ["op-1", "op-2"]  # oldest first
    assert history[0] == {"operation": "op-1", "source": "TU_B", "target": "TU_D",
                          "module": "TM_1", "outcome": "delivered", "face": "back",
                          "conveyor": "left", "theta_deg": -15, "submitted": 10.0,
                          "finished": 40.0}  # fmt: skip


def test_a_running_transfer_shows_its_state_once_it_transfers() -> None:
    done = op("op-1", submitted=10.0)
    planned = {"face": "front", "conveyor": "right", "theta_deg": 5}
    driving = op("op-2", submitted=20.0, state="running", plan=planned,
                 steps=((21.0, "navigating", "TU_B"), (25.0, "docking", "TU_B")))  # fmt: skip
    assert shown("o2", [done, driving])["Face"] == "back"
    moving = op("op-2", submitted=20.0, state="running", plan=planned,
                steps=((21.0, "navigating", "TU_B"), (26.0, "transferring", "TU_B")))  # fmt: skip
    got = shown("o2", [done, moving])
    assert (got["Face"], got["Conveyor"], got["Theta"]) == ("front", "right", math.radians(5))
    assert got["LastTransfer"] == "delivered"  # the running one has no outcome yet
    assert len(json.loads(got["TransferHistoryJson"])) == 1


def test_the_history_keeps_the_latest_transfers() -> None:
    ops = [op(f"op-{i}", submitted=float(i)) for i in range(HISTORY_LIMIT + 5)]
    history = json.loads(shown("o2", ops)["TransferHistoryJson"])
    assert len(history) == HISTORY_LIMIT and history[-1]["operation"] == f"op-{HISTORY_LIMIT + 4}"


def test_every_shown_value_is_a_property_of_the_objects_aas() -> None:
    rep = build_representation(next(d for d in demo_descriptors() if d.asset_id == "o2"))
    props = {p.id_short: p for p in rep.submodel("OperationalData").submodel_element}
    for name, value in shown("o2", [op("op-1", submitted=1.0)]).items():
        assert type(value) is type(props[name].value), name
