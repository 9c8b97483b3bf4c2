"""The transport operation flow of Fig. 5.9a on the demo floor in one process (real asyncua
servers on loopback): the transport module navigates the shop floor, docks by laser with the
error that emerges there, forms the OTS from its depth camera's scan and transfers; its
states and pose are published over OPC UA. And the OTS refused on what a real scan sees."""

from __future__ import annotations

import asyncio
import json
import math

import numpy as np
import pytest

from transfertwin.cps import LocalFloor, default_floor_spec
from transfertwin.cps.apps import HOME_POSE, STEPS, Environment, form_ots
from transfertwin.navigation import default_floor, relative
from transfertwin.ots import BeltThresholds, TransferDirection
from transfertwin.perception import CameraIntrinsics, DepthCamera, Workspace, workspace_scan
from transfertwin.sim import DockingError, SceneConfig, tu_pose_in_tip_frame


def _dedup(states: list[str]) -> list[str]:
    return [s for i, s in enumerate(states) if i == 0 or s != states[i - 1]]


@pytest.mark.slow  # ~20-40 s (CI: the CPS slow group)
def test_a_navigated_order_runs_navigate_dock_scan_transfer_in_order(tmp_path, cps_certs):
    async def scenario():
        wd = cps_certs(tmp_path)
        async with LocalFloor(default_floor_spec(), wd, time_scale=0.0,
                              docking="navigated") as cps:  # fmt: skip
            seen: list[str] = []
            done = asyncio.Event()

            class States:
                def datachange_notification(self, node, val, data):
                    seen.append(val)

            class Completed:
                def datachange_notification(self, node, val, data):
                    if val >= 1:
                        done.set()

            pose_props = ("PoseX", "PoseY", "PoseTheta")
            kg = cps.nodes["KG"].role.kg
            async with cps.client("TM_1", role="viewer") as tm, cps.client("TMS") as tms:
                home = [await tm.read("OperationalData", p) for p in pose_props]
                assert home == list(HOME_POSE)
                await tm.subscribe(States(), ("OperationalData", "State"))
                await tms.subscribe(Completed(), ("OperationalData", "CompletedOperations"))
                op = await tms.call("SubmitTransportOperation", "TU_B", "TU_D", "o2")
                await asyncio.wait_for(done.wait(), timeout=240)
                for _ in range(100):  # the module's last change may trail the TMS's
                    if seen and seen[-1] == "idle" and len(seen) > 1:
                        break
                    await asyncio.sleep(0.1)
                pose = np.array([await tm.read("OperationalData", p) for p in pose_props])
                docked_at = await tm.read("OperationalData", "DockedAt")
                record = json.loads(await tms.call("OperationStatus", op))
                ledger = json.loads(await tms.call("Ledger"))
                for _ in range(100):  # the graph hears the module's state by its heartbeats
                    if kg.idle_transport_modules() == ["TM_1"]:
                        break
                    await asyncio.sleep(0.1)
            result = record["result"]
            assert record["operation"] == op and result["docking"] == "navigated"

            # The states, as a client of TM_1 saw them, in the flow's order.
            states = result["states"]
            assert states[:4] == list(STEPS) and states[-1] == "idle"
            if result["y_pickup"] == 1:  # the delivery leg follows the pick-up
                assert states[4:8] == list(STEPS)
            assert _dedup(seen) == ["idle", *_dedup(states)], seen
            assert kg.idle_transport_modules() == ["TM_1"] and docked_at == ""

            # The emergent docking error of each leg is recorded, and it is the error of the
            # pose the module stands at (published over OPC UA) from the station's goal.
            floor = default_floor()
            for leg in result["legs"]:
                d = leg["docking"]
                assert d["status"] == "ok" and leg["navigating"]["path_m"] > 1.0
                assert abs(d["x_mm"]) < 50 and abs(d["y_mm"]) < 50 and abs(d["theta_deg"]) < 5
            last = result["legs"][-1]["docking"]
            xi = relative(floor.station(last["station"]).goal_pose(), pose)
            got = (xi[0] * 1000, xi[1] * 1000, math.degrees(xi[2]))
            assert np.allclose(got, (last["x_mm"], last["y_mm"], last["theta_deg"]), atol=1e-3)
            assert not np.allclose(pose, HOME_POSE)
            # ... and the MuJoCo environment docked with it, or with PropS's fused estimate
            # of it where PropS answered (what the twin knows of the docking)
            props = last.get("props") or {}
            used = props["fused"] if props.get("used") == "fused" else last
            err = DockingError.from_mm_deg(used["x_mm"], used["y_mm"], used["theta_deg"])
            module = cps.nodes["TM_1"].role
            scene = module.env.scene
            want = tu_pose_in_tip_frame(err, scene.gap_m, scene.layout.tip_to_centre_m)
            assert np.allclose(module.env.system.tu_pose, want, atol=1e-5)

            # The OTS was formed from the depth camera's scan: the object on the giving unit.
            pickup = result["legs"][0]["scanning"]
            assert pickup["source"] == "depth camera" and len(pickup["boxes"]) == 1
            assert pickup["boxes"][0]["x"] > 0.0  # on TU_B, ahead of the module's tip
            where = {"delivered": "TU_D", "failed at pick-up": "TU_B",
                     "failed at delivery": "TM_1"}[result["status"]]  # fmt: skip
            assert ledger["locations"]["o2"] == where == record["location"]

    asyncio.run(asyncio.wait_for(scenario(), timeout=600))


def test_the_ots_is_refused_on_what_the_scan_sees(tmp_path):
    scene = SceneConfig()
    env = Environment(scene)
    env.load_object_at_unit("o2", "TU_B", DockingError.from_mm_deg(-6.0, 4.0, 0.8))
    workspace = Workspace.for_layout(scene.layout, scene.gap_m, docked=True)
    with DepthCamera(env.system.model, env.system.data, intrinsics=CameraIntrinsics(160, 120),
                     noise=None) as camera:  # fmt: skip
        detection, _ = workspace_scan(camera, workspace, seed=3)
    th = BeltThresholds(t_max=scene.t_max_s)
    kw = {"obj": "o2", "tm": "TM_1", "unit": "TU_B"}
    pickup = form_ots(detection.boxes, TransferDirection.TU_TO_TM, th, **kw)
    assert pickup.ok, pickup.reason
    # A delivery to TU_B now: its belts are taken, and o2 is not on the module.
    delivery = form_ots(detection.boxes, TransferDirection.TM_TO_TU, th, **kw)
    assert not delivery.ok
    assert delivery.reason.startswith("target belts occupied: 1 object(s) seen on TU_B")
    # The module's representation says it still carries o5 (a failed delivery before).
    held = form_ots(detection.boxes, TransferDirection.TU_TO_TM, th, receiver_holds=("o5",),
                    **kw)  # fmt: skip
    assert held.reason == "target belts occupied: TM_1 holds o5"
