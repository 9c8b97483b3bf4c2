"""Perception in the loop (issue 14, item 6): the OTS controller fed by the depth camera."""

from __future__ import annotations

import math

import numpy as np
import pytest

from transfertwin._errors import InputError
from transfertwin.ots import POSITIONS, TransferDirection
from transfertwin.perception import PerceptionSensor, camera_pose, open_sensor
from transfertwin.sim import DockingError, SceneConfig
from transfertwin.study.experiment import (
    ExperimentSpec,
    run_experiment,
    scene_controller,
    system_for,
)

SCENE = SceneConfig()


class _Watched:
    """The perception sensor, plus where the true object was in each frame it took."""

    def __init__(self, sensor: PerceptionSensor) -> None:
        self.sensor = sensor
        self.pixels: list[np.ndarray] = []  # the true AABB's corners in the image, (8, 2)
        self.aim_deg: list[float] = []  # angle between the optical axis and the true centre

    def observe(self) -> np.ndarray:
        alpha = self.sensor.alpha_rad  # the angle this frame is taken at
        obs = self.sensor.observe()
        truth = self.sensor.system.observe()
        centre, half = truth[1:4], truth[4:7]
        pose = camera_pose(self.sensor.camera.rig, alpha)
        signs = np.array([[a, b, c] for a in (-1, 1) for b in (-1, 1) for c in (-1, 1)])
        corners_c = (centre + signs * half - pose[:3, 3]) @ pose[:3, :3]
        f = self.sensor.camera.intrinsics.focal_px
        self.pixels.append(f * corners_c[:, :2] / corners_c[:, 2:])
        p_c = pose[:3, :3].T @ (centre - pose[:3, 3])
        self.aim_deg.append(math.degrees(math.atan2(math.hypot(p_c[0], p_c[1]), p_c[2])))
        return obs


def test_camera_follows_the_object_through_a_transfer() -> None:
    """o23 front on both belts: the TM → TU transfer succeeds as with ground truth, the
    servo turns from the TM's belts to the TU's and the object never leaves the image."""
    system = system_for("o23", "m", SCENE)
    truth_y = []
    for mode in ("truth", "perception"):
        system.reset(DockingError())
        system.place("front", 0.0, *POSITIONS["both"])
        system.clock.wait(SCENE.placement.settle_time_s)
        if mode == "truth":
            ctrl = scene_controller(SCENE, system.tm, system.tu, system, system.clock)
            truth_y.append(ctrl.transfer(TransferDirection.TM_TO_TU, "front", "both").y)
            continue
        with open_sensor(system, expected_xy=POSITIONS["both"], theta_rad=0.0, seed=3) as sensor:
            watched = _Watched(sensor)
            ctrl = scene_controller(SCENE, system.tm, system.tu, watched, system.clock)
            record = ctrl.transfer(TransferDirection.TM_TO_TU, "front", "both")
    assert truth_y == [1]
    assert record.y == 1
    alphas = np.degrees(sensor.alphas)
    assert len(alphas) == len(watched.pixels) > 30
    assert alphas[-1] - alphas[0] > 25.0  # from above the TM's belts to the TU's
    assert np.all(np.diff(alphas) > -1.0)  # it turns with the object, never back
    w, h = sensor.camera.intrinsics.width, sensor.camera.intrinsics.height
    corners = np.concatenate(watched.pixels)  # pixel offsets from the image centre
    assert np.all(np.abs(corners[:, 0]) < 0.5 * w) and np.all(np.abs(corners[:, 1]) < 0.5 * h)
    assert max(watched.aim_deg[1:]) < 3.0  # aimed at the object from the 2nd frame on


def test_unknown_sensor_is_refused() -> None:
    with pytest.raises(InputError, match="sensor"):
        run_experiment(ExperimentSpec("o23", "front", "both", 0), sensor="sonar")


@pytest.mark.slow
def test_perception_driven_experiment_matches_ground_truth_on_an_easy_state() -> None:
    """E^V there and back: same outcome, t_end within a few samples, same bits per seed."""
    spec = ExperimentSpec("o23", "back", "left", 90, seed=2)
    truth = run_experiment(spec)
    seen = [run_experiment(spec, sensor="perception") for _ in range(2)]
    assert (truth.status, truth.y1, truth.y2) == ("ok", 1, 1)
    assert (seen[0].status, seen[0].y1, seen[0].y2) == ("ok", 1, 1)
    assert abs(seen[0].t_end_s - truth.t_end_s) < 5 / SCENE.camera_rate_hz
    assert seen[0].row() == seen[1].row()
    other = run_experiment(spec, sensor="perception", perception_seed=9)
    assert other.state_pre != seen[0].state_pre  # the camera's draws follow its seed
