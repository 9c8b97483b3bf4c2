"""Perception in the loop: the OTS controller fed by the camera.

`open_sensor` forms the transport module's view of an OTS the way Sec. 5.5 describes it:
scan the workspace from the two viewpoints (α = 20°, −30°), take the detection nearest to
where the operation says the object lies, turn the servo onto it (Eq. 5.14) and hand back
a `PerceptionSensor` that renders, detects, tracks and re-aims once per controller sample.
`transfertwin.study.experiment.run_experiment(spec, sensor="perception")` uses it in place of
the ground-truth readout.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

from transfertwin.perception._camera import CameraIntrinsics, DepthCamera
from transfertwin.perception._detector import DetectorConfig
from transfertwin.perception._frames import ServoRig
from transfertwin.perception._noise import DepthNoise
from transfertwin.perception._scan import workspace_scan
from transfertwin.perception._sensor import PerceptionSensor
from transfertwin.perception._servo import servo_angle
from transfertwin.perception._tracker import TrackerConfig
from transfertwin.perception._workspace import Workspace
from transfertwin.sim import VirtualTransferSystem

__all__ = ["PerceptionConfig", "open_sensor"]


@dataclass(frozen=True)
class PerceptionConfig:
    """The camera and pipeline used in the loop.

    Attributes:
        intrinsics: Image size and field of view. 160x120 by default (not the 320x240 of
            `transfertwin perceive`): every controller sample renders and detects one frame,
            and the detector's error at 160x120 is the one docs/perception.md reports.
        noise: Depth noise and dropout.
        rig: Servo and camera mounting.
        detector: Detector parameters (Fig. 5.14).
        tracker: Tracker parameters (Sec. 5.4.3).
    """

    intrinsics: CameraIntrinsics = field(default_factory=lambda: CameraIntrinsics(160, 120))
    noise: DepthNoise = field(default_factory=DepthNoise)
    rig: ServoRig = field(default_factory=ServoRig)
    detector: DetectorConfig = field(default_factory=DetectorConfig)
    tracker: TrackerConfig = field(default_factory=TrackerConfig)


def open_sensor(
    system: VirtualTransferSystem,
    *,
    expected_xy: tuple[float, float],
    theta_rad: float,
    config: PerceptionConfig | None = None,
    seed: int = 0,
) -> PerceptionSensor:
    """Scan, aim and return the sensor that follows the object (it owns its camera: use it
    as a context manager or call `close`).

    Args:
        system: The virtual system, object placed and settled.
        expected_xy: Where the operation expects the object (x, y) in F_T, e.g. the
            nominal position of its conveyor; the scan's detection nearest to it is aimed at.
            With no detection the servo stays at 0 (looking down at the TM's belts).
        theta_rad: The yaw the sensor reports (not observable from an AABB).
        config: Camera and pipeline.
        seed: The scan's frames use `seed`, `seed + 1`; the sensor's frame k `seed + 2 + k`.
    """
    cfg = config if config is not None else PerceptionConfig()
    camera = DepthCamera(system.model, system.data, cfg.rig, cfg.intrinsics, cfg.noise)
    try:
        workspace = Workspace.for_layout(system.cfg.layout, system.cfg.gap_m, docked=True)
        scan, views = workspace_scan(camera, workspace, cfg=cfg.detector, seed=seed)
        alpha = 0.0
        if scan.boxes:
            target = min(scan.boxes, key=lambda b: math.dist(b.centre[:2], expected_xy))
            alpha = cfg.rig.clip(servo_angle(cfg.rig, target.centre[0], target.centre[2])[0])
    except BaseException:
        camera.close()
        raise
    return PerceptionSensor(
        system, camera, workspace, theta_rad=theta_rad, alpha_rad=alpha,
        detector=cfg.detector, tracker=cfg.tracker, seed=seed + len(views), owns_camera=True,
    )  # fmt: skip
