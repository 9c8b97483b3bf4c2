"""Dubins paths and Hybrid A* respect the curvature limit and avoid obstacles (Sec. 5.5)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from transfertwin.navigation import (
    Rect,
    RobotConfig,
    default_floor,
    dubins_shortest,
    plan_path,
    sample_segments,
    wrap_angle,
)


def _curvature(poses: np.ndarray) -> np.ndarray:
    """Curvature between samples from the poses alone: a circular arc turning by Δθ over a chord
    c has κ = 2·sin(|Δθ|/2) / c (exact for arcs and straight pieces)."""
    chord = np.linalg.norm(np.diff(poses[:, :2], axis=0), axis=1)
    return 2.0 * np.sin(np.abs(wrap_angle(np.diff(poses[:, 2]))) / 2.0) / chord


def test_dubins_paths_end_at_the_goal_and_turn_no_tighter_than_the_radius() -> None:
    rng = np.random.default_rng(7)
    for _ in range(200):
        q0 = np.r_[rng.uniform(-3, 3, 2), rng.uniform(-math.pi, math.pi)]
        q1 = np.r_[rng.uniform(-3, 3, 2), rng.uniform(-math.pi, math.pi)]
        path = dubins_shortest(q0, q1, 0.5)
        poses, _ = sample_segments(q0, path.segments(), 0.02)
        assert np.allclose(poses[-1, :2], q1[:2], atol=1e-9)
        assert abs(wrap_angle(poses[-1, 2] - q1[2])) < 1e-9
        assert _curvature(poses).max() <= 2.0 * (1 + 1e-6)
        straight = np.linalg.norm(q1[:2] - q0[:2])
        assert path.length_m >= straight - 1e-9


def test_dubins_straight_ahead_is_the_segment() -> None:
    path = dubins_shortest(np.zeros(3), np.array([2.0, 0.0, 0.0]), 0.5)
    assert path.length_m == pytest.approx(2.0)


def _footprint_hits(floor, robot: RobotConfig, poses: np.ndarray) -> int:
    """Occupied grid cells inside the true rectangular footprint (not the planner's circles)."""
    ii, jj = np.nonzero(floor.grid)
    cells = np.stack([(jj + 0.5) * floor.resolution_m, (ii + 0.5) * floor.resolution_m], 1)
    hits = 0
    for p in poses[::4]:
        near = cells[np.linalg.norm(cells - p[:2], axis=1) < 1.0]
        rect = Rect(p[0], p[1], robot.length_m, robot.width_m, p[2])
        hits += int(rect.contains(near).sum()) if len(near) else 0
    return hits


@pytest.mark.parametrize(("start", "goal"), [("D", "A"), ("A", "B"), ("B", "C"), ("A", "D")])
def test_planned_paths_respect_the_curvature_limit_and_avoid_obstacles(start, goal) -> None:
    floor, robot = default_floor(), RobotConfig()
    s = floor.station(start).coarse_pose(0.7)
    s[2] += math.pi  # turned away from the station it leaves
    g = floor.station(goal).coarse_pose(0.7)
    path = plan_path(floor, robot, s, g)
    assert np.allclose(path.poses[0], s, atol=1e-9)
    assert np.allclose(path.poses[-1, :2], g[:2], atol=1e-6)
    assert _curvature(path.poses).max() <= robot.max_curvature * (1 + 1e-6)
    assert _footprint_hits(floor, robot, path.poses) == 0
    assert path.length_m >= np.linalg.norm(g[:2] - s[:2])
