"""Global path planning to the coarse docking pose under the curvature constraint: Hybrid A*
(Dolgov et al. 2010) with Dubins analytic expansion (Sec. 5.4.1, 5.5).

Search nodes are continuous poses binned by (x, y, θ) cells; each expansion drives a forward
arc of `step_m` with one of five curvatures in [-κ_max, κ_max]. The heuristic is the larger of
the obstacle-free Dubins length and the 8-connected grid distance to the goal around obstacles
(Dijkstra on the occupancy grid). When the search gets near the goal it tries a Dubins path to
it; the first collision-free one ends the search, so the goal pose is reached exactly.
Collision checks cover the footprint with three circles tested on the clearance map.
"""

from __future__ import annotations

import heapq
import math
from dataclasses import dataclass

import numpy as np
from scipy import sparse
from scipy.sparse import csgraph

from transfertwin._errors import InputError
from transfertwin.navigation._dubins import dubins_shortest, sample_segments
from transfertwin.navigation._floor import ShopFloor
from transfertwin.navigation._robot import RobotConfig

__all__ = ["Path", "PlannerConfig", "collision_free", "plan_path"]


@dataclass(frozen=True)
class PlannerConfig:
    """Hybrid A* settings.

    Attributes:
        step_m: Arc length of one expansion, m.
        xy_cell_m: Position bin, m.
        heading_bins: Heading bins over 360°.
        margin_m: Extra clearance beyond the footprint circles, m.
        steer_cost: Extra cost per metre driven on a curve, relative.
        expand_radius_m: Try the Dubins shot when this close (heuristic), m.
        max_expansions: Give up after this many expansions.
        sample_m: Spacing of the returned path's poses, m.
    """

    step_m: float = 0.3
    xy_cell_m: float = 0.15
    heading_bins: int = 72
    margin_m: float = 0.05
    steer_cost: float = 0.1
    expand_radius_m: float = 4.0
    max_expansions: int = 20000
    sample_m: float = 0.05


@dataclass(frozen=True)
class Path:
    """A planned path: poses (M, 3), the curvature (M,) driven into each, 1/m."""

    poses: np.ndarray
    curvature: np.ndarray

    @property
    def length_m(self) -> float:
        """Length along the samples, m."""
        return float(np.sum(np.linalg.norm(np.diff(self.poses[:, :2], axis=0), axis=1)))


def collision_free(
    floor: ShopFloor, robot: RobotConfig, poses: np.ndarray, margin_m: float
) -> bool:
    """Whether every pose (M, 3) keeps the footprint circles `margin_m` clear of solids."""
    centres, radius = robot.footprint_circles()
    p = np.atleast_2d(poses)
    c, s = np.cos(p[:, 2]), np.sin(p[:, 2])
    wx = p[:, None, 0] + c[:, None] * centres[None, :, 0] - s[:, None] * centres[None, :, 1]
    wy = p[:, None, 1] + s[:, None] * centres[None, :, 0] + c[:, None] * centres[None, :, 1]
    clear = floor.clearance_at(np.stack([wx.ravel(), wy.ravel()], axis=1))
    return bool(np.all(clear > radius + margin_m))


def _grid_distance(floor: ShopFloor, goal: np.ndarray, free_radius: float) -> np.ndarray:
    """8-connected shortest distance (H, W) from the goal cell over cells with clearance
    above `free_radius`, m (inf where unreachable)."""
    free = floor.clearance > free_radius
    h, w = free.shape
    ids = np.arange(h * w).reshape(h, w)
    rows, cols, vals = [], [], []
    for di, dj in ((0, 1), (1, 0), (1, 1), (1, -1)):
        i0, i1 = max(0, -di), h - max(0, di)
        j0, j1 = max(0, -dj), w - max(0, dj)
        a = ids[i0:i1, j0:j1]
        b = ids[i0 + di : i1 + di, j0 + dj : j1 + dj]
        ok = free.ravel()[a.ravel()] & free.ravel()[b.ravel()]
        rows.append(a.ravel()[ok])
        cols.append(b.ravel()[ok])
        vals.append(np.full(ok.sum(), math.hypot(di, dj) * floor.resolution_m))
    graph = sparse.coo_matrix(
        (np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))), shape=(h * w, h * w)
    ).tocsr()
    gi = int(goal[1] / floor.resolution_m)
    gj = int(goal[0] / floor.resolution_m)
    dist = csgraph.dijkstra(graph, directed=False, indices=gi * w + gj)
    return dist.reshape(h, w)


def plan_path(
    floor: ShopFloor,
    robot: RobotConfig,
    start: np.ndarray,
    goal: np.ndarray,
    cfg: PlannerConfig = PlannerConfig(),
) -> Path:
    """A collision-free forward path from `start` to `goal` with curvature ≤ κ_max.

    Raises:
        InputError: Start or goal in collision, or no path within `max_expansions`.
    """
    radius = robot.min_turn_radius_m
    kmax = robot.max_curvature
    for name, q in (("start", start), ("goal", goal)):
        if not collision_free(floor, robot, q, cfg.margin_m):
            raise InputError(f"path planning: the {name} pose {np.round(q, 3)} is in collision")
    grid = _grid_distance(floor, goal, robot.width_m / 2.0)
    res = floor.resolution_m

    def heuristic(q: np.ndarray) -> float:
        i, j = int(q[1] / res), int(q[0] / res)
        g = grid[i, j] if 0 <= i < grid.shape[0] and 0 <= j < grid.shape[1] else math.inf
        return max(dubins_shortest(q, goal, radius).length_m, g)

    def key(q: np.ndarray) -> tuple[int, int, int]:
        th = int(((q[2] % (2 * math.pi)) / (2 * math.pi)) * cfg.heading_bins) % cfg.heading_bins
        return int(q[0] // cfg.xy_cell_m), int(q[1] // cfg.xy_cell_m), th

    curvatures = (-kmax, -kmax / 2, 0.0, kmax / 2, kmax)
    nodes = [(np.asarray(start, dtype=float), -1, 0.0, 0.0)]  # pose, parent, curvature, g
    heap = [(heuristic(nodes[0][0]), 0)]
    closed: set[tuple[int, int, int]] = set()
    for _ in range(cfg.max_expansions):
        if not heap:
            break
        f, n = heapq.heappop(heap)
        q, _, _, g = nodes[n]
        k = key(q)
        if k in closed:
            continue
        closed.add(k)
        if f - g < cfg.expand_radius_m:
            shot = dubins_shortest(q, goal, radius)
            poses, curv = sample_segments(q, shot.segments(), cfg.sample_m)
            if collision_free(floor, robot, poses, cfg.margin_m):
                return _assemble(nodes, n, poses, curv, cfg)
        for kappa in curvatures:
            poses, _ = sample_segments(q, [(kappa, cfg.step_m)], cfg.sample_m * 2)
            nq = poses[-1]
            if key(nq) in closed or not collision_free(floor, robot, poses[1:], cfg.margin_m):
                continue
            ng = g + cfg.step_m * (1.0 + cfg.steer_cost * abs(kappa) / kmax)
            nodes.append((nq, n, kappa, ng))
            heapq.heappush(heap, (ng + heuristic(nq), len(nodes) - 1))
    raise InputError(f"path planning: no path from {np.round(start, 2)} to {np.round(goal, 2)}")


def _assemble(nodes: list, n: int, tail: np.ndarray, tail_curv: np.ndarray, cfg: PlannerConfig):
    """The path from the start through node n and the final Dubins shot."""
    chain = []
    while nodes[n][1] >= 0:
        chain.append(n)
        n = nodes[n][1]
    poses, curv = [nodes[n][0][None, :]], [np.array([0.0])]
    q = nodes[n][0]
    for m in reversed(chain):
        p, c = sample_segments(q, [(nodes[m][2], cfg.step_m)], cfg.sample_m)
        poses.append(p[1:])
        curv.append(c[1:])
        q = p[-1]
    poses.append(tail[1:])
    curv.append(tail_curv[1:])
    out_c = np.concatenate(curv)
    if len(out_c) > 1:
        out_c[0] = out_c[1]
    return Path(np.concatenate(poses), out_c)
