"""Following a planned path with pure pursuit, on odometry corrected by global localisation.

The robot steers towards the point `lookahead_m` ahead on the path as its *belief* sees it;
the belief integrates wheel odometry and is reset every `MotionNoise.loc_period_s` to the true
pose plus the localisation noise (an AMCL-like fix on the occupancy grid). The body moves with
wheel slip (`drive`). The drive ends when the belief has passed the path's last pose; the robot
then turns on the spot until its belief heading is within `heading_tol_rad` of the path's end.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from transfertwin.navigation._geometry import compose, relative
from transfertwin.navigation._planner import Path
from transfertwin.navigation._robot import MotionNoise, RobotConfig, drive

__all__ = ["FollowConfig", "FollowResult", "follow_path", "localise"]


@dataclass(frozen=True)
class FollowConfig:
    """Pure-pursuit settings: lookahead (m), control step (s), time limit (s)."""

    lookahead_m: float = 0.4
    dt_s: float = 0.1
    max_time_s: float = 120.0
    heading_tol_rad: float = math.radians(1.0)


@dataclass(frozen=True)
class FollowResult:
    """True poses driven (K, 3), final true pose, final belief, final odometry pose."""

    trace: np.ndarray
    truth: np.ndarray
    belief: np.ndarray
    odom: np.ndarray


def localise(truth: np.ndarray, noise: MotionNoise, rng: np.random.Generator) -> np.ndarray:
    """A global localisation fix: the true pose plus Gaussian noise."""
    sd = np.array([noise.loc_xy_sd_m, noise.loc_xy_sd_m, noise.loc_theta_sd_rad])
    return compose(truth, rng.normal(0.0, 1.0, 3) * sd)


def follow_path(
    path: Path,
    truth: np.ndarray,
    robot: RobotConfig,
    noise: MotionNoise,
    scale: np.ndarray,
    rng: np.random.Generator,
    cfg: FollowConfig = FollowConfig(),
) -> FollowResult:
    """Drive along `path` from the true pose `truth` (see the module docstring)."""
    end = path.poses[-1]
    ext = compose(end, np.array([cfg.lookahead_m * 2, 0.0, 0.0]))
    pts = np.vstack([path.poses[:, :2], ext[:2]])
    belief = localise(truth, noise, rng)
    odom = belief.copy()
    trace, t, idx, last_fix = [truth], 0.0, 0, 0.0
    while t < cfg.max_time_s:
        if relative(end, belief)[0] >= 0.0 and idx >= len(path.poses) - 2:
            break
        window = pts[idx : idx + 40]
        idx += int(np.argmin(np.linalg.norm(window - belief[:2], axis=1)))
        ahead = np.linalg.norm(pts[idx:] - belief[:2], axis=1)
        far = np.flatnonzero(ahead >= cfg.lookahead_m)
        target = pts[idx + (far[0] if len(far) else len(ahead) - 1)]
        local = relative(belief, np.array([*target, 0.0]))
        kappa = 2.0 * local[1] / max(local[0] ** 2 + local[1] ** 2, 1e-6)
        kappa = float(np.clip(kappa, -robot.max_curvature, robot.max_curvature))
        remaining = max(-relative(end, belief)[0], 0.0)
        v = min(robot.cruise_m_s, max(0.05, remaining))
        new_truth, new_odom = drive(truth, odom, v, v * kappa, cfg.dt_s, robot, scale, rng, noise)
        belief = compose(belief, relative(odom, new_odom))
        truth, odom, t = new_truth, new_odom, t + cfg.dt_s
        trace.append(truth)
        if t - last_fix >= noise.loc_period_s:
            belief, last_fix = localise(truth, noise, rng), t
    while t < cfg.max_time_s:
        err = float(relative(end, belief)[2])
        if abs(err) < cfg.heading_tol_rad:
            break
        w = float(np.clip(-2.0 * err, -0.5, 0.5))
        new_truth, new_odom = drive(truth, odom, 0.0, w, cfg.dt_s, robot, scale, rng, noise)
        belief = compose(belief, relative(odom, new_odom))
        truth, odom, t = new_truth, new_odom, t + cfg.dt_s
        trace.append(truth)
    return FollowResult(np.array(trace), truth, belief, odom)
