"""A transport module on real hardware (``[hal] kind = "remote"``): its drive, pose, belts,
barriers and object sensor are a HAL gateway's nodes, and so are the two transfer units'
belts and barriers. The gateway is a real asyncua server whose nodes a MuJoCo transfer
system drives in real time (`_plant_gateway`); the module, the units and the gateway talk
OPC UA only. One transport operation runs end to end through it; one whose object the
module's sensor does not see where the order says it is fails at forming the OTS; one whose
delivery the machine cannot dock for fails at docking with the object on the module. A
pick-up whose belts jam is taken back and tried again, with PropS fusing the module's
localisation into the docking error."""

from __future__ import annotations

import asyncio
import dataclasses
import json
import time
from pathlib import Path

import numpy as np
import pytest

from tests.integration.cps._plant_gateway import PlantGateway
from transfertwin.cps import (
    AssetConfig,
    AssetNode,
    HalConfig,
    asset_node,
    connect,
    default_floor_spec,
    floor_toml,
)
from transfertwin.cps.opcua import free_port

UNITS = {"TU_A": "A", "TU_B": "B"}


def _configs(tmp_path: Path, gateway: str) -> dict[str, AssetConfig]:
    spec = default_floor_spec()
    stations = tuple(dataclasses.replace(s, hal="remote", gateway=gateway)
                     if s.unit in UNITS else s for s in spec.stations)  # fmt: skip
    modules = (dataclasses.replace(spec.modules[0], hal="remote", gateway=gateway),)
    spec = dataclasses.replace(spec, stations=stations, modules=modules)
    (tmp_path / "floor.toml").write_text(floor_toml(spec))
    out = {}
    for aid in (*UNITS, "TM_1"):
        hal = HalConfig("remote", endpoint=gateway, insecure=True, poll_s=0.02)
        out[aid] = AssetConfig(asset_id=aid, floor_file=tmp_path / "floor.toml",
                               host="127.0.0.1", port=free_port(), seeds=(),
                               cert_dir=tmp_path / aid / "certs",
                               trust_dir=tmp_path / aid / "trusted", credentials_file=None,
                               state_dir=tmp_path / aid / "state", insecure=True,
                               hal=hal)  # fmt: skip
    return out


async def _until(check, timeout_s: float, what: str):
    t0 = time.monotonic()
    while True:
        value = await check()
        if value:
            return value
        assert time.monotonic() - t0 < timeout_s, f"{what}: not within {timeout_s} s"
        await asyncio.sleep(0.05)


def _events(node: AssetNode, op_id: str) -> list[dict]:
    """The module's reports of `op_id` (no TMS on this floor: they stay in its outbox)."""
    return [e for o, e in node.role.state.data["outbox"] if o == op_id]


async def _finished(node: AssetNode, op_id: str) -> dict | None:
    """`op_id`'s result as the module reported it (None while it runs)."""
    done = [e for e in _events(node, op_id) if e["event"] == "result"]
    return done[0]["result"] if done else None


def _delivered(plant: PlantGateway, scenario) -> dict:
    """Run `scenario` (the plant is stopped either way); its first operation delivered."""
    try:
        out = asyncio.run(scenario())
    finally:
        plant.stop()
    result = out["result"]
    assert result["status"] == "delivered", (result, plant.log.drive, plant.log.jammed_s)
    assert (result["y_pickup"], result["y_delivery"]) == (1, 1)
    return out


@pytest.mark.slow  # real time: three transfers and fifteen drive commands, ~25 s
def test_a_remote_module_transfers_through_its_gateway_end_to_end(tmp_path):
    port = free_port()
    # o2 lies on TU_B (the demo placement); the plant's physics is the only truth
    plant = PlantGateway(port, "TM_1", UNITS, "o2", at="TU_B", seed=11).start()
    cfgs = _configs(tmp_path, plant.url)

    async def scenario() -> dict:
        async with asset_node(cfgs["TU_A"]) as tu_a, asset_node(cfgs["TU_B"]) as tu_b, \
                asset_node(cfgs["TM_1"]) as tm:
            for unit in (tu_a, tu_b):
                tm.learn(unit.desc.asset_id, unit.server.endpoint)
            async with connect(tm.server.endpoint, "TM_1", credentials=None,
                               insecure=True) as client:  # fmt: skip
                # the pose the module publishes is its machine's
                assert await client.read("OperationalData", "PoseX") == pytest.approx(6.0)
                assert await client.call("AssignOperation", "op1", "TU_B", "TU_A", "o2", "{}")

                result = await _until(lambda: _finished(tm, "op1"), 90, "op1")
                pose = [await client.read("OperationalData", k) for k in ("PoseX", "PoseY")]
                # the module's published pose is the gateway's (docked at A, then undocked)
                assert pose == pytest.approx(list(plant.pose[:2]), abs=1e-9)
                possessed = await client.read("OperationalData", "PossessedObjects")
                # the sensor sees nothing on TU_B now: no OTS, no transfer
                assert await client.call("AssignOperation", "op2", "TU_B", "TU_A", "o2", "{}")
                second = await _until(lambda: _finished(tm, "op2"), 60, "op2")
                holder = plant.holder  # where the physics has the object after op1 and op2
                # the machine cannot dock at C (the plant has no unit there): the delivery
                # fails at docking, the object stays on the module, the drive leaves C
                assert await client.call("AssignOperation", "op3", "TU_A", "TU_C", "o2", "{}")
                third = await _until(lambda: _finished(tm, "op3"), 90, "op3")
                third["possessed"] = await client.read("OperationalData", "PossessedObjects")
                return {"result": result, "possessed": possessed, "second": second,
                        "holder": holder, "third": third,
                        "moved": [e for e in _events(tm, "op1") if e["event"] == "moved"]}

    out = _delivered(plant, scenario)
    result = out["result"]
    assert [(e["object"], e["holder"]) for e in out["moved"]] == [("o2", "TM_1"), ("o2", "TU_A")]
    assert out["possessed"] == ""
    # the physics agrees: the object lies on TU_A's belts
    assert out["holder"] == "TU_A"
    # the module drove and docked through its gateway, leg by leg (op1, op2, op3)
    assert plant.log.commands == ["navigate B", "dock B", "undock", "navigate A", "dock A",
                                  "undock", "navigate B", "dock B", "undock",
                                  "navigate A", "dock A", "undock", "navigate C", "dock C",
                                  "undock"]  # fmt: skip
    # the docking errors the module recorded are what its localisation at the gateway said
    for leg, (station, xi) in zip(result["legs"], plant.log.errors, strict=False):
        assert station == UNITS[leg["unit"]]
        rec = leg["docking"]
        assert rec["x_mm"] == pytest.approx(xi[0] * 1e3, abs=2e-3)
        assert rec["y_mm"] == pytest.approx(xi[1] * 1e3, abs=2e-3)
        assert rec["theta_deg"] == pytest.approx(np.degrees(xi[2]), abs=2e-4)
        # the OTS was formed from the gateway's object sensor
        assert leg["scanning"]["source"] == "object sensor at the gateway"
        assert len(leg["scanning"]["boxes"]) == 1
    # all four belt pairs ran at the gateway (the units' through their own processes), and
    # the receivers' barriers saw the object arrive
    for asset in ("TM_1", "TU_A", "TU_B"):
        assert plant.log.belts[f"{asset}.BeltSpeedLeft"] == pytest.approx(0.15)
    assert "TU_A.BarrierNear" in plant.log.barriers and "TM_1.BarrierNear" in plant.log.barriers
    second = out["second"]
    assert second["status"] == "failed at pick-up" and second["failed_step"] == "scanning"
    assert "o2 not seen on TU_B" in second["reason"]
    third = out["third"]
    assert third["status"] == "failed at delivery" and third["failed_step"] == "docking"
    assert "no unit at C" in third["reason"] and third["y_pickup"] == 1
    assert third["possessed"] == "o2" and plant.holder == "TM_1"
    json.dumps(result)  # the report is JSON as the TMS gets it


@pytest.mark.slow  # real time: a jammed transfer, a take-back and three transfers, ~30 s
def test_a_failed_pickup_is_taken_back_and_retried_through_the_gateway_with_props(tmp_path):
    """The module's belt drive trips at the first pick-up (its belts stand still: the
    object does not arrive); the module reverses both belt pairs through the gateway and
    the unit, the object goes back onto TU_B, the module undocks, docks anew by command and
    the second try delivers. PropS runs on the floor: each docking reports the module's
    localisation at the gateway and the leg's docking error is PropS's fused estimate."""
    port = free_port()
    plant = PlantGateway(port, "TM_1", UNITS, "o2", at="TU_B", seed=12, jam=True).start()
    cfgs = _configs(tmp_path, plant.url)
    cfgs["PropS"] = dataclasses.replace(cfgs["TU_A"], asset_id="PropS", port=free_port(),
                                        hal=HalConfig(), cert_dir=tmp_path / "PropS" / "certs",
                                        trust_dir=tmp_path / "PropS" / "trusted",
                                        state_dir=tmp_path / "PropS" / "state")  # fmt: skip

    async def scenario() -> dict:
        async with asset_node(cfgs["TU_A"]) as tu_a, asset_node(cfgs["TU_B"]) as tu_b, \
                asset_node(cfgs["PropS"]) as props, asset_node(cfgs["TM_1"]) as tm:
            for peer in (tu_a, tu_b, props):
                tm.learn(peer.desc.asset_id, peer.server.endpoint)
            async with connect(tm.server.endpoint, "TM_1", credentials=None,
                               insecure=True) as client:  # fmt: skip
                assert await client.call("AssignOperation", "op1", "TU_B", "TU_A", "o2", "{}")
                result = await _until(lambda: _finished(tm, "op1"), 120, "op1")
            async with connect(props.server.endpoint, "PropS", credentials=None,
                               insecure=True) as ps:  # fmt: skip
                fused = json.loads(await ps.read("OperationalData", "FusedPosesJson"))
                errors = json.loads(await ps.read("OperationalData", "DockingErrorsJson"))
            return {"result": result, "fused": fused, "errors": errors}

    out = _delivered(plant, scenario)
    result = out["result"]
    pick = result["legs"][0]
    tries = pick["transferring"]["retries"]
    assert [(t["attempt"], t["taken_back"]) for t in tries] == [(1, True)]
    assert "did not reach the receiver" in tries[0]["reason"]
    assert plant.log.jammed_s > 1.0  # the drive really stood still through the first try
    # taken back: TU_B's belts ran towards the module and back (through TU_B's process)
    assert plant.log.signs["TU_B.BeltSpeedLeft"] == {-1, 1}
    # the pick-up was docked for anew by command, without driving away
    assert plant.log.commands == ["navigate B", "dock B", "undock", "dock B", "undock",
                                  "navigate A", "dock A", "undock"]  # fmt: skip
    assert plant.holder == "TU_A"  # the physics agrees: delivered
    # PropS in the loop: the docking error recorded is its fused estimate of the module's
    # localisation fix (the only observation of the module: the same error, σ of the fix)
    for leg, (station, xi) in zip(result["legs"], [plant.log.errors[0], plant.log.errors[2]],
                                  strict=True):  # fmt: skip
        rec = leg["docking"]
        assert station == UNITS[leg["unit"]] and rec["source"] == "PropS's fused estimate"
        assert rec["props"]["used"] == "fused" and rec["props"]["camera"] is False
        assert rec["x_mm"] == pytest.approx(xi[0] * 1e3, abs=0.01)
        assert rec["y_mm"] == pytest.approx(xi[1] * 1e3, abs=0.01)
        assert rec["theta_deg"] == pytest.approx(np.degrees(xi[2]), abs=1e-3)
        assert rec["props"]["gateway"]["x_mm"] == pytest.approx(xi[0] * 1e3, abs=2e-3)
        assert 15.0 < rec["props"]["fused"]["sd_x_mm"] < 25.0  # the 20 mm fix, 2 mm survey
    assert out["errors"]["TM_1"]["unit"] == "TU_A"
    # PropS holds the pose the gateway reported at the last docking (at A; undocking
    # leaves the module where it stands)
    assert out["fused"]["TM_1"]["x"] == pytest.approx(plant.pose[0], abs=1e-6)
