"""The AAS a running floor serves: nothing advertised that no role implements, and objects
that show their state (the demo floor in one process, real asyncua servers on loopback).

* Every operation in an asset's served ControlInterface has a handler on its server (a
  call of one without answers BadNotImplemented); a capability's relations and constraints
  are nodes of the server.
* After an order the object's AAS, read over OPC UA, holds where it lies, the face,
  conveyor and yaw it was transferred in, the outcome, and its transfer history.
"""

from __future__ import annotations

import asyncio
import json
import math

import basyx.aas.model as aas
import pytest

from transfertwin.cps import LocalFloor, default_floor_spec


def unimplemented(floor: LocalFloor) -> dict[str, list[str]]:
    """Per asset the ControlInterface operations its server has no handler for."""
    missing = {}
    for aid, node in floor.nodes.items():
        server = node.server
        ops = [el.id_short for sm in server.submodels if sm.id_short == "ControlInterface"
               for el in sm.submodel_element if isinstance(el, aas.Operation)]  # fmt: skip
        if gaps := [op for op in ops if op not in server.handlers]:
            missing[aid] = gaps
    return missing


@pytest.mark.slow  # ~20-40 s (CI: the CPS slow group)
def test_served_operations_are_implemented_and_an_object_shows_its_transfer(tmp_path, cps_certs):
    async def scenario():
        wd = cps_certs(tmp_path)
        async with LocalFloor(default_floor_spec(), wd, time_scale=0.0) as floor:
            assert set(floor.nodes) >= {"TU_A", "TM_1", "o2", "TMS", "EM", "PropS", "KG"}
            assert unimplemented(floor) == {}
            async with floor.client("TM_1", role="viewer") as tm:  # the capability pattern
                width = await tm.read("Capabilities", "TransferRelations.Constraints.BeltWidth")
                dock = await tm.read("Capabilities", "TransferRelations.RealizedByDock.Second")
                cap = await tm.read("Capabilities", "TransferRelations.RealizedByDock.First")
            assert width == 0.195
            assert dock.endswith("/sm/TM_1/ControlInterface/Dock")
            assert cap.endswith("/sm/TM_1/Capabilities/Transfer")

            done = asyncio.Event()

            class Watch:
                def datachange_notification(self, node, val, data):
                    if val >= 1:
                        done.set()

            async with floor.client("TMS") as tms:
                await tms.subscribe(Watch(), ("OperationalData", "CompletedOperations"))
                op = await tms.call("SubmitTransportOperation", "TU_B", "TU_D", "o2")
                await asyncio.wait_for(done.wait(), timeout=240)
                record = json.loads(await tms.call("OperationStatus", op))
            outcome = record["result"]["status"]
            state = record["result"]["loaded_state"] or record["plan"]["state"]
            assert state is not None  # the predictive floor chose one

            names = ("PossessedBy", "Face", "Conveyor", "Theta", "LastTransfer",
                     "TransferHistoryJson")  # fmt: skip
            async with floor.client("o2", role="viewer") as o2:
                for _ in range(100):  # the TMS publishes within a second
                    shown = {n: await o2.read("OperationalData", n) for n in names}
                    if shown["LastTransfer"]:
                        break
                    await asyncio.sleep(0.1)
            assert shown["PossessedBy"] == record["location"]
            assert shown["LastTransfer"] == outcome
            assert (shown["Face"], shown["Conveyor"]) == (state["face"], state["conveyor"])
            assert shown["Theta"] == pytest.approx(math.radians(state["theta_deg"]))
            (entry,) = json.loads(shown["TransferHistoryJson"])
            assert (entry["operation"], entry["outcome"], entry["module"]) == (op, outcome, "TM_1")
            assert (entry["source"], entry["target"]) == ("TU_B", "TU_D")

            # the object's process keeps what it was shown across a restart
            await floor.stop("o2")
            await floor.start("o2")
            async with floor.client("o2", role="viewer") as o2:
                again = {n: await o2.read("OperationalData", n) for n in names}
            assert again == shown

    asyncio.run(asyncio.wait_for(scenario(), timeout=300))
