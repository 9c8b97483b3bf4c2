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
    from transfertwin.cps import AssetNode, load_floor, prepare_floor
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
        async with AssetNode(cfg) as node, connect(node.server.endpoint, "PropS",
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
