"""Perception in the loop: an `ObjectSensor` that sees the object through the camera.

`PerceptionSensor` stands in for the ground-truth readout of `VirtualTransferSystem.observe`
in the OTS controller (`transfertwin.control.ObjectSensor`). Each `observe()` is one camera
frame: render depth at the servo's current angle, detect (Fig. 5.14), track with the belt
speeds as control input (Sec. 5.4.3), then turn the servo onto the followed track for the
next frame (Sec. 5.4.4) — the camera follows the object during a transfer.

What perception cannot know is filled in as the real TM does:
- the yaw θ is not observable from an AABB (Sec. 5.4.2): the value given at construction
  (the operation's pre-transfer state) is returned unchanged;
- possession a: the TU's when the tracked centre lies beyond the middle of the nominal gap;
- before the first detection, and if the track is lost, the state is NaN (no state set
  contains it, so a controller treats it as invalid / not terminal).
"""

from __future__ import annotations

import math

import numpy as np

from transfertwin.perception._aabb import AABB
from transfertwin.perception._camera import DepthCamera
from transfertwin.perception._detector import DetectorConfig, detect
from transfertwin.perception._frames import camera_pose
from transfertwin.perception._servo import servo_angle
from transfertwin.perception._tracker import Track, Tracker, TrackerConfig
from transfertwin.perception._workspace import Workspace
from transfertwin.sim import VirtualTransferSystem

__all__ = ["PerceptionSensor"]


class PerceptionSensor:
    """The vision system as the controller's object sensor.

    Args:
        system: The virtual system (rendered; its belt HALs give the control input).
        camera: A depth camera on `system`'s model and data.
        workspace: Detector workspace.
        theta_rad: The yaw reported (not observable).
        alpha_rad: Initial servo angle.
        detector, tracker: Parameters.
        seed: Seed of frame k's noise and RANSAC draws is `seed + k`.
        owns_camera: `close` (or leaving the `with` block) closes the camera.
    """

    def __init__(
        self,
        system: VirtualTransferSystem,
        camera: DepthCamera,
        workspace: Workspace,
        *,
        theta_rad: float = 0.0,
        alpha_rad: float = 0.0,
        detector: DetectorConfig | None = None,
        tracker: TrackerConfig | None = None,
        seed: int = 0,
        owns_camera: bool = False,
    ) -> None:
        self.system, self.camera, self.workspace = system, camera, workspace
        self.theta_rad = theta_rad
        self.alpha_rad = alpha_rad
        self.detector = detector
        self.tracker = Tracker(tracker)
        self.seed = seed
        self.frames = 0
        self.followed: int | None = None
        self.alphas: list[float] = []
        self._last_t: float | None = None
        self._owns_camera = owns_camera

    def __enter__(self) -> PerceptionSensor:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def close(self) -> None:
        """Free the camera's renderer if this sensor opened it (`open_sensor`)."""
        if self._owns_camera:
            self.camera.close()
            self._owns_camera = False

    def _belt_velocity(self, centre: np.ndarray) -> np.ndarray:
        """(v_x, v_y) of the belt(s) under a centre: the unit by x, the belt by the sign of y
        (both belts' mean on the centre line)."""
        hal = self.system.tu if centre[0] > 0.5 * self.system.cfg.gap_m else self.system.tm
        speeds = [hal.belt_speed("left"), hal.belt_speed("right")]
        v = speeds[0] if centre[1] > 0.005 else speeds[1] if centre[1] < -0.005 else np.mean(speeds)
        return np.array([v, 0.0])

    def _followed_track(self) -> Track | None:
        for tr in self.tracker.tracks:
            if tr.track_id == self.followed:
                return tr
        tracks = sorted(self.tracker.tracks, key=lambda t: -t.box.n_points)
        self.followed = tracks[0].track_id if tracks else None
        return tracks[0] if tracks else None

    def observe(self) -> np.ndarray:
        """(a, x, y, z, s_x, s_y, s_z, θ) of the followed object in F_T, shape (8,)."""
        t = float(self.system.data.time)
        dt = 0.0 if self._last_t is None else t - self._last_t
        self._last_t = t
        view = self.camera.capture(self.alpha_rad, self.seed + self.frames)
        boxes = detect([view], self.workspace, self.detector, seed=self.seed + self.frames).boxes
        self.frames += 1
        self.tracker.step(boxes, dt, self._belt_velocity)
        track = self._followed_track()
        self.alphas.append(self.alpha_rad)
        if track is None:
            return np.full(8, np.nan)
        box: AABB = track.aabb()
        alpha, _ = servo_angle(self.camera.rig, box.centre[0], box.centre[2])
        self.alpha_rad = self.camera.rig.clip(alpha)
        a = float(box.centre[0] > 0.5 * self.system.cfg.gap_m)
        return np.array([a, *box.centre, *box.half, self.theta_rad])

    def aim_error_rad(self, xyz: tuple[float, float, float]) -> float:
        """Angle (rad) between the current optical axis and the ray to a point in F_T."""
        pose = camera_pose(self.camera.rig, self.alpha_rad)
        ray = np.asarray(xyz) - pose[:3, 3]
        cos = float(pose[:3, 2] @ ray / np.linalg.norm(ray))
        return math.acos(min(1.0, max(-1.0, cos)))
