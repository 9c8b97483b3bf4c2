"""The final approach: laser docking-pose estimates and a line-following controller
(Sec. 5.4.1).

Every `scan_period_s` the robot scans, estimates the docking goal from the station's outer
edge (`estimate_dock_pose`) and stores it in the odometry frame; the goal it steers to is the
mean of the last `window` estimates. Between scans it moves on odometry. The controller
tracks the goal's x axis: with (e_x, e_y, e_θ) the robot's pose in the goal frame,

    v = clip(k_v · (−e_x), v_min, v_dock),   ω = −v · (k_y · e_y + k_θ · sin e_θ),

(a kinematic path-following law; k_y = 64 m⁻², k_θ = 16 m⁻¹ make the lateral error critically
damped over about half a metre) and stops as soon as e_x ≥ −tol_x: the robot stops short of
the goal by up to the tolerance, which is the controller's share of the docking error.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from transfertwin.navigation._dock_pose import DockEstimate, estimate_dock_pose
from transfertwin.navigation._floor import Station
from transfertwin.navigation._geometry import compose, relative
from transfertwin.navigation._laser import LaserConfig, Scan, scan
from transfertwin.navigation._lines import SegmentationConfig
from transfertwin.navigation._robot import MotionNoise, RobotConfig, drive

__all__ = ["ApproachConfig", "ApproachResult", "approach"]


@dataclass(frozen=True)
class ApproachConfig:
    """Final-approach controller (see the module docstring).

    Attributes:
        dt_s: Control step, s.
        scan_period_s: Time between laser estimates, s.
        window: Estimates averaged.
        k_v: Speed gain, 1/s.
        k_y: Lateral gain, 1/m².
        k_theta: Heading gain, 1/m.
        v_min_m_s: Slowest commanded speed, m/s.
        tol_x_m: Stop when the goal is less than this far ahead, m.
        max_time_s: Give up after this long, s.
    """

    dt_s: float = 0.05
    scan_period_s: float = 0.2
    window: int = 5
    k_v: float = 1.0
    k_y: float = 64.0
    k_theta: float = 16.0
    v_min_m_s: float = 0.02
    tol_x_m: float = 0.008
    max_time_s: float = 30.0


@dataclass(frozen=True)
class ApproachResult:
    """Outcome: status ('ok', 'no_line', 'timeout'), true poses (K, 3), final true pose, the
    last scan with the scanner's true pose, and the last estimate (None: never one)."""

    status: str
    trace: np.ndarray
    truth: np.ndarray
    last_scan: Scan
    laser_pose: np.ndarray
    estimate: DockEstimate | None


def _mean_pose(poses: list[np.ndarray]) -> np.ndarray:
    p = np.array(poses)
    return np.array(
        [*p[:, :2].mean(axis=0), math.atan2(np.sin(p[:, 2]).sum(), np.cos(p[:, 2]).sum())]
    )


def approach(
    station: Station,
    truth: np.ndarray,
    belief: np.ndarray,
    segments: np.ndarray,
    robot: RobotConfig,
    laser: LaserConfig,
    seg: SegmentationConfig,
    noise: MotionNoise,
    scale: np.ndarray,
    rng: np.random.Generator,
    cfg: ApproachConfig = ApproachConfig(),
) -> ApproachResult:
    """Dock at `station` from the coarse pose (true pose `truth`, belief `belief`)."""
    odom = belief.copy()  # odometry frame = the belief at the start of the approach
    bias = laser.range_bias(rng)
    mount_true = np.array([*robot.laser_xy_m, robot.laser_yaw_rad + laser.mount_yaw_error_rad])
    goals: list[np.ndarray] = []
    trace, estimate, t, next_scan = [truth], None, 0.0, 0.0
    status = "timeout"
    while t < cfg.max_time_s:
        if t >= next_scan - 1e-9:
            laser_pose = compose(truth, mount_true)
            last = scan(segments, laser_pose, laser, rng, bias)
            est = estimate_dock_pose(
                last, station, relative(odom, station.edge_pose), robot, laser, seg
            )
            if est is not None:
                estimate = est
                goals = [*goals, compose(odom, est.goal)][-cfg.window :]
            next_scan += cfg.scan_period_s
        if not goals:
            status = "no_line"
            break
        ex, ey, eth = relative(_mean_pose(goals), odom)
        if ex >= -cfg.tol_x_m:
            status = "ok"
            break
        v = float(np.clip(cfg.k_v * -ex, cfg.v_min_m_s, robot.dock_speed_m_s))
        w = float(np.clip(-v * (cfg.k_y * ey + cfg.k_theta * math.sin(eth)), -1.0, 1.0))
        truth, odom = drive(truth, odom, v, w, cfg.dt_s, robot, scale, rng, noise)
        trace.append(truth)
        t += cfg.dt_s
    laser_pose = compose(truth, mount_true)
    final = scan(segments, laser_pose, laser, rng, bias)
    return ApproachResult(status, np.array(trace), truth, final, laser_pose, estimate)
