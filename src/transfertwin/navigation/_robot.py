"""The transport module as a differential-drive robot: footprint, laser mount, limits and
the noise of its motion (wheel slip, odometry) and of its global localisation.

Chosen values (the study gives none; they are typical of a 0.8 m × 0.5 m AMR):

- wheel base 0.45 m; drive speed 0.4 m/s on the floor, 0.1 m/s when docking;
- minimum turning radius 0.5 m for the global planner (the curvature constraint, Sec. 5.5);
- wheel slip: each run draws a scale error per wheel, N(0, 0.3 %) (tyre wear, load), and each
  control step adds N(0, 2 %) of the step's travel per wheel; odometry integrates the encoder
  values, the body moves with the slipping ones;
- global localisation (AMCL-like, on the occupancy grid): every 1 s the robot's belief is
  reset to the truth plus N(0, 20 mm) in x and y and N(0, 0.8°) in heading.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from transfertwin._errors import InputError
from transfertwin.navigation._geometry import wrap_angle

__all__ = ["MotionNoise", "RobotConfig", "drive"]


@dataclass(frozen=True)
class RobotConfig:
    """Geometry and limits of the transport module (F_D at its centre, x forward).

    Attributes:
        length_m, width_m: Footprint, m.
        wheel_base_m: Distance between the drive wheels, m.
        laser_xy_m: Scanner position in F_D (front-left corner), m.
        laser_yaw_rad: Scanner's zero direction in F_D, rad (45°: the 270° field covers the
            front and the left side).
        min_turn_radius_m: Curvature limit of planned paths, m.
        cruise_m_s: Path-following speed, m/s.
        dock_speed_m_s: Top speed of the final approach, m/s.
    """

    length_m: float = 0.8
    width_m: float = 0.5
    wheel_base_m: float = 0.45
    laser_xy_m: tuple[float, float] = (0.37, 0.22)
    laser_yaw_rad: float = math.pi / 4
    min_turn_radius_m: float = 0.5
    cruise_m_s: float = 0.4
    dock_speed_m_s: float = 0.1

    def __post_init__(self) -> None:
        if min(self.length_m, self.width_m, self.wheel_base_m, self.min_turn_radius_m) <= 0:
            raise InputError("RobotConfig: sizes and the turning radius must be positive")

    @property
    def max_curvature(self) -> float:
        """κ_max = 1 / minimum turning radius, 1/m."""
        return 1.0 / self.min_turn_radius_m

    def footprint_circles(self) -> tuple[np.ndarray, float]:
        """Three circles covering the footprint: centres (3, 2) in F_D and their radius, m."""
        third = self.length_m / 3.0
        centres = np.array([[-third, 0.0], [0.0, 0.0], [third, 0.0]])
        return centres, math.hypot(third / 2.0, self.width_m / 2.0)

    def footprint(self) -> np.ndarray:
        """Footprint corners (4, 2) in F_D, counter-clockwise from the rear right."""
        hl, hw = self.length_m / 2.0, self.width_m / 2.0
        return np.array([[-hl, -hw], [hl, -hw], [hl, hw], [-hl, hw]])


@dataclass(frozen=True)
class MotionNoise:
    """Wheel slip and localisation noise (1σ values; see the module docstring).

    Attributes:
        wheel_scale_sd: Per-run relative scale error of each wheel.
        wheel_step_sd: Per-step relative slip of each wheel's travel.
        loc_xy_sd_m: Global localisation error per axis, m.
        loc_theta_sd_rad: Global localisation heading error, rad.
        loc_period_s: Time between localisation updates, s.
    """

    wheel_scale_sd: float = 0.003
    wheel_step_sd: float = 0.02
    loc_xy_sd_m: float = 0.02
    loc_theta_sd_rad: float = math.radians(0.8)
    loc_period_s: float = 1.0

    def __post_init__(self) -> None:
        values = (self.wheel_scale_sd, self.wheel_step_sd, self.loc_xy_sd_m, self.loc_theta_sd_rad)
        if min(values) < 0 or self.loc_period_s <= 0:
            raise InputError("MotionNoise: standard deviations must be >= 0, period > 0")


def _integrate(pose: np.ndarray, dl: float, dr: float, base: float) -> np.ndarray:
    """Pose after the wheels travel dl, dr (m): exact arc of a differential drive."""
    ds, dth = (dl + dr) / 2.0, (dr - dl) / base
    th = pose[2]
    if abs(dth) < 1e-9:
        dx, dy = ds * math.cos(th), ds * math.sin(th)
    else:
        r = ds / dth
        dx = r * (math.sin(th + dth) - math.sin(th))
        dy = -r * (math.cos(th + dth) - math.cos(th))
    return np.array([pose[0] + dx, pose[1] + dy, float(wrap_angle(th + dth))])


def drive(
    truth: np.ndarray,
    odom: np.ndarray,
    v: float,
    w: float,
    dt: float,
    robot: RobotConfig,
    scale: np.ndarray,
    rng: np.random.Generator | None,
    noise: MotionNoise,
) -> tuple[np.ndarray, np.ndarray]:
    """One control step: the commanded (v, ω) moves the body with slip; odometry integrates
    the encoders.

    Args:
        truth, odom: True and odometry pose (3,) before the step.
        v, w: Commanded speed (m/s) and turn rate (rad/s).
        dt: Step, s.
        robot: Wheel base.
        scale: Per-run wheel scale errors (2,) (left, right).
        rng: Per-step slip source; None: no per-step slip.
        noise: Slip standard deviation.

    Returns:
        (truth, odom) after the step.
    """
    half = w * robot.wheel_base_m / 2.0
    dl, dr = (v - half) * dt, (v + half) * dt
    slip = np.zeros(2) if rng is None else rng.normal(0.0, noise.wheel_step_sd, 2)
    tl, tr = dl * (1.0 + scale[0] + slip[0]), dr * (1.0 + scale[1] + slip[1])
    return _integrate(truth, tl, tr, robot.wheel_base_m), _integrate(
        odom, dl, dr, robot.wheel_base_m
    )
