"""Ray casting, split-and-merge and the edge-based docking-pose estimate (Sec. 5.4.1)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from transfertwin.navigation import (
    LaserConfig,
    RobotConfig,
    SegmentationConfig,
    cast_rays,
    compose,
    default_floor,
    estimate_dock_pose,
    relative,
    scan,
    split_and_merge,
)


def test_ray_hits_a_wall_at_the_analytic_distance_and_incidence() -> None:
    wall = np.array([[[2.0, -5.0], [2.0, 5.0]]])
    a = math.radians(30)
    dist, cos_inc = cast_rays(np.zeros(2), np.array([[math.cos(a), math.sin(a)]]), wall)
    assert dist[0] == pytest.approx(2.0 / math.cos(a))
    assert cos_inc[0] == pytest.approx(math.cos(a))


def test_split_and_merge_finds_the_two_legs_of_a_corner() -> None:
    angles = np.radians(np.arange(-40.0, 130.0, 0.5))
    segs = np.array([[[1.0, -2.0], [1.0, 1.0]], [[1.0, 1.0], [-2.0, 1.0]]])
    dirs = np.stack([np.cos(angles), np.sin(angles)], 1)
    dist, _ = cast_rays(np.zeros(2), dirs, segs)
    ranges = dist + np.random.default_rng(0).normal(0, 0.005, len(dist))
    pts = np.stack([ranges * np.cos(angles), ranges * np.sin(angles)], 1)
    lines = split_and_merge(pts, ranges, math.radians(0.5), SegmentationConfig(range_sd_m=0.005))
    assert len(lines) == 2
    vertical, horizontal = sorted(lines, key=lambda ln: abs(ln.direction[0]))
    assert abs(vertical.direction[0]) < 0.02 and abs(vertical.centroid[0] - 1.0) < 0.01
    assert abs(horizontal.direction[1]) < 0.02 and abs(horizontal.centroid[1] - 1.0) < 0.01


def test_noise_free_estimate_at_the_goal_is_exact_up_to_the_beam_spacing() -> None:
    floor, robot = default_floor(), RobotConfig()
    laser = LaserConfig(mount_yaw_error_rad=0.0)
    mount = np.array([*robot.laser_xy_m, robot.laser_yaw_rad])
    for station in floor.stations:
        truth = station.goal_pose()
        laser_pose = compose(truth, mount)
        sweep = scan(floor.segments, laser_pose, laser, None)
        expected = relative(truth, station.edge_pose)
        est = estimate_dock_pose(sweep, station, expected, robot, laser, SegmentationConfig())
        assert est is not None
        err = relative(relative(truth, station.goal_pose()), est.goal)
        edge_range = np.linalg.norm(relative(laser_pose, station.edge_pose)[:2])
        incidence = math.atan2(abs(relative(station.edge_pose, laser_pose)[1]), 0.15)
        spacing = edge_range * laser.step_rad / math.cos(incidence)
        assert abs(err[0]) < 1e-3 and abs(err[2]) < math.radians(0.05)
        assert abs(err[1]) <= spacing + 1e-4
