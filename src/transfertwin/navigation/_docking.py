"""One docking run end to end: start near the previous station, plan to the target's coarse
pose, follow the path, dock by laser; the docking error ξ emerges (Sec. 5.4.1, Eq. 6.11).

The run starts where the previous station in the cycle A → B → C → D → A left the robot: at
that station's coarse pose, turned on the spot to face away from it, with a random offset
(N(0, 50 mm) per axis, N(0, 3°)). Every random draw comes from one generator seeded by
(seed, station, run), so a run is a pure function of its arguments.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from transfertwin._errors import InputError
from transfertwin.navigation._approach import ApproachConfig, ApproachResult, approach
from transfertwin.navigation._floor import ShopFloor
from transfertwin.navigation._follow import FollowConfig, follow_path
from transfertwin.navigation._geometry import compose, relative
from transfertwin.navigation._laser import LaserConfig
from transfertwin.navigation._lines import SegmentationConfig
from transfertwin.navigation._planner import Path, PlannerConfig, collision_free, plan_path
from transfertwin.navigation._robot import MotionNoise, RobotConfig

__all__ = ["DockingConfig", "DockingRun", "dock_runs", "simulate_docking"]


@dataclass(frozen=True)
class DockingConfig:
    """Everything a docking run depends on besides the floor and the seed.

    Attributes:
        robot, laser, segmentation, planner, noise, follow, approach: The sections.
        coarse_distance_m: How far before the goal the global planner stops, m (Sec. 5.5:
            far enough that the final approach is feasible under the curvature limit).
        start_xy_sd_m, start_theta_sd_rad: Spread of the start pose.
    """

    robot: RobotConfig = field(default_factory=RobotConfig)
    laser: LaserConfig = field(default_factory=LaserConfig)
    segmentation: SegmentationConfig = field(default_factory=SegmentationConfig)
    planner: PlannerConfig = field(default_factory=PlannerConfig)
    noise: MotionNoise = field(default_factory=MotionNoise)
    follow: FollowConfig = field(default_factory=FollowConfig)
    approach: ApproachConfig = field(default_factory=ApproachConfig)
    coarse_distance_m: float = 0.7
    start_xy_sd_m: float = 0.05
    start_theta_sd_rad: float = math.radians(3.0)


@dataclass(frozen=True)
class DockingRun:
    """One run's outcome.

    Attributes:
        station: Target station name.
        run: Run index.
        status: 'ok', 'no_line' (no matching line seen) or 'timeout'.
        error: True docking error ξ = pose of F_D in F_D_G (x m, y m, θ rad), Eq. 6.11.
        start: True start pose (3,).
        path: The planned path.
        trace: True poses driven (K, 3).
        approach: The final approach (last scan, scanner pose, last estimate).
    """

    station: str
    run: int
    status: str
    error: np.ndarray
    start: np.ndarray
    path: Path
    trace: np.ndarray
    approach: ApproachResult


def _previous(floor: ShopFloor, name: str) -> str:
    names = floor.station_names
    return names[(names.index(name) - 1) % len(names)]


def _start_pose(floor: ShopFloor, name: str, cfg: DockingConfig, rng: np.random.Generator):
    base = floor.station(_previous(floor, name)).coarse_pose(cfg.coarse_distance_m)
    base = compose(base, np.array([0.0, 0.0, math.pi]))
    sd = np.array([cfg.start_xy_sd_m, cfg.start_xy_sd_m, cfg.start_theta_sd_rad])
    for _ in range(100):
        start = compose(base, rng.normal(0.0, 1.0, 3) * sd)
        if collision_free(floor, cfg.robot, start, cfg.planner.margin_m):
            return start
    raise InputError(f"station {name}: no collision-free start pose near the previous station")


def simulate_docking(
    floor: ShopFloor, station: str, seed: int, run: int = 0, cfg: DockingConfig = DockingConfig()
) -> DockingRun:
    """Navigate to and dock at `station`; a pure function of (floor, station, seed, run, cfg)."""
    target = floor.station(station)
    index = floor.station_names.index(station)
    rng = np.random.default_rng(np.random.SeedSequence([seed, index, run]))
    start = _start_pose(floor, station, cfg, rng)
    path = plan_path(
        floor, cfg.robot, start, target.coarse_pose(cfg.coarse_distance_m), cfg.planner
    )
    scale = rng.normal(0.0, cfg.noise.wheel_scale_sd, 2)
    driven = follow_path(path, start, cfg.robot, cfg.noise, scale, rng, cfg.follow)
    docked = approach(
        target,
        driven.truth,
        driven.belief,
        floor.segments,
        cfg.robot,
        cfg.laser,
        cfg.segmentation,
        cfg.noise,
        scale,
        rng,
        cfg.approach,
    )
    error = relative(target.goal_pose(), docked.truth)
    trace = np.vstack([driven.trace, docked.trace[1:]])
    return DockingRun(station, run, docked.status, error, start, path, trace, docked)


def dock_runs(
    floor: ShopFloor,
    station: str,
    runs: int,
    seed: int,
    cfg: DockingConfig = DockingConfig(),
    on_progress=None,
) -> list[DockingRun]:
    """`runs` docking runs at `station` (run indices 0..runs-1), reporting
    `on_progress(done, total)` after each."""
    out = []
    for r in range(runs):
        out.append(simulate_docking(floor, station, seed, r, cfg))
        if on_progress is not None:
            on_progress(r + 1, runs)
    return out
