"""PropS in the loop (issue 28, item 4), its node in this process over OPC UA: the units'
surveyed poses from the floor, a module's localisation fix and a unit camera's ChArUco
measurement fused into the docking error with its uncertainty, published as variables; a
module that reports a new pose of itself drops the stale camera edge."""

from __future__ import annotations

import asyncio
import dataclasses
import json
import math

import numpy as np
import pytest

from tests.integration.cps.test_em_study import FLOOR


def test_props_fuses_a_modules_fix_and_a_camera_observation_into_the_docking_error(tmp_path):
    from transfertwin.cps import asset_node, load_floor, prepare_floor
    from transfertwin.cps.apps import Pose2D
    from transfertwin.cps.opcua import connect
    from transfertwin.navigation import CharucoRig

    floor = FLOOR.replace('logical = ["KG", "TMS", "EM"]', 'logical = ["KG", "TMS", "PropS"]')
    (tmp_path / "floor.toml").write_text(floor)
    spec = load_floor(tmp_path / "floor.toml")
    configs = prepare_floor(spec, tmp_path / "w", insecure=True)
    cfg = dataclasses.replace(configs["PropS"], seeds=())
    goal = Pose2D(*spec.shop_floor().station("A").goal_pose())
    truth = np.array([0.0042, -0.0071, 0.012])  # the true docking error at TU_A
    seen = CharucoRig(pixel_noise_sd=3.0).measure_error(truth, np.random.default_rng(1))
    module = goal.compose(Pose2D(*truth))

    async def main():
        async with asset_node(cfg) as node, connect(node.server.endpoint, "PropS",
                                                  credentials=None, insecure=True) as ps:
            fused = json.loads(await ps.read("OperationalData", "FusedPosesJson"))
            assert fused["TU_A"]["x"] == pytest.approx(goal.x, abs=1e-6)  # from the floor
            await ps.call("ReportPose", "TM_1", "TM_1", module.x + 0.02, module.y - 0.01,
                          module.theta, 0.02, 0.014)  # fmt: skip
            await ps.call("ReportRelativePose", "TU_A/camera", "TM_1", "TU_A",
                          *(float(v) for v in seen), 1e-4, 5e-4)  # fmt: skip
            est = json.loads(await ps.call("DockingError", "TM_1", "TU_A"))
            published = json.loads(await ps.read("OperationalData", "DockingErrorsJson"))
            fused = json.loads(await ps.read("OperationalData", "FusedPosesJson"))
            # the module moved on: its own new pose drops the camera edge
            await ps.call("ReportPose", "TM_1", "TM_1", 6.0, 5.2, 0.0, 0.02, 0.014)
            stale = json.loads(await ps.call("DockingError", "TM_1", "TU_A"))
            return est, published, fused, stale

    est, published, fused, stale = asyncio.run(main())
    # within 3 of the camera's declared sigmas of the truth
    assert (est["x_m"], est["y_m"]) == pytest.approx(tuple(truth[:2]), abs=3e-4)
    assert est["theta_rad"] == pytest.approx(truth[2], abs=1.5e-3)
    assert est["sd_x_m"] <= 1e-4 and est["sd_theta_rad"] <= 5e-4
    assert est["sources"] == ["TM_1", "TU_A/camera"]
    assert published["TM_1"]["unit"] == "TU_A" and published["TM_1"]["x_m"] == est["x_m"]
    assert set(fused) == {"TU_A", "TM_1"} and fused["TM_1"]["sd_x"] < 0.0025
    assert stale["sources"] == ["TM_1"] and stale["sd_x_m"] > 0.01  # the fix alone
    assert math.hypot(stale["x_m"], stale["y_m"]) > 1.0


PROPS_FLOOR = """
name = "props-loop"
size_m = [12.0, 8.0]
logical = ["KG", "TMS", "PropS"]

[[station]]
name = "A"
x_m = 2.6
y_m = 6.6
yaw_deg = 90.0
mount = "left"

[[station]]
name = "B"
x_m = 7.6
y_m = 6.6
yaw_deg = 90.0
mount = "right"

[[module]]
id = "TM_1"
x_m = 6.0
y_m = 5.2

[[object]]
id = "o1"
at = "TU_A"
"""


@pytest.mark.slow
def test_an_order_on_a_floor_docks_with_the_fused_estimate(tmp_path):
    from pathlib import Path

    from tests.integration.cps._cli import tt
    from transfertwin.cli._cps_client import call_asset, load_info

    (tmp_path / "floor.toml").write_text(PROPS_FLOOR)
    wd = tmp_path / "w"
    up = tt("cps", "up", "--policy", "nearest-idle",
            "--floor", str(tmp_path / "floor.toml"), "--workdir", str(wd),
            "--detach", "--time-scale", "0", "--lease", "3", "--start-timeout", "150",
            timeout=200)  # fmt: skip
    assert up.returncode == 0, up.stderr
    try:
        order = tt("cps", "order", "--workdir", str(wd), "--object", "o1", "--to", "TU_B")
        assert order.returncode in (0, 3), order.stderr  # delivered, or failed as a transfer may
        info, creds = load_info(Path(wd))
        op = json.loads(asyncio.run(call_asset(info, creds, "TMS", "OperationStatus", "op1")))
        # the units told PropS where they stand (their own processes, over OPC UA)
        units = [json.loads(asyncio.run(call_asset(info, creds, "PropS", "FusedPose", u)))
                 for u in ("TU_A", "TU_B")]  # fmt: skip
    finally:
        tt("cps", "down", "--workdir", str(wd))
    assert all(u["reported"] and u["sd_x"] <= 0.0025 for u in units), units
    docked = [leg["docking"]["props"] for leg in op["result"]["legs"] if "docking" in leg]
    assert docked, op["result"]
    for props in docked:
        assert props["used"] == "fused" and props["camera"], props
        true, fused = props["true"], props["fused"]
        assert abs(fused["x_mm"] - true["x_mm"]) < 3 * max(fused["sd_x_mm"], 0.1)
        assert abs(fused["y_mm"] - true["y_mm"]) < 3 * max(fused["sd_y_mm"], 0.1)
        assert abs(fused["theta_deg"] - true["theta_deg"]) < 3 * max(fused["sd_theta_deg"], 0.03)
