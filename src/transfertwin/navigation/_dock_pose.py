"""Docking-pose estimation from the station cuboid's outer edge (Sec. 5.4.1, Fig. 5.10b).

The scan is segmented into lines; among them the line that matches the target station's
configuration is chosen: at least `min_fraction` of the face's length, roughly parallel to the
expected front face (within `max_angle_rad`), its reference end within `gate_m` of where the map
and the robot's belief put the outer edge, and, of those, the one nearest to the robot. Its
reference end (the left end for a left-mounted transfer unit, the right end for a right-mounted
one) and its normal give the edge frame; the docking goal is the station's configured offset
from that frame.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from transfertwin.navigation._floor import Station
from transfertwin.navigation._geometry import compose, to_world, wrap_angle
from transfertwin.navigation._laser import LaserConfig, Scan
from transfertwin.navigation._lines import LineSegment, SegmentationConfig, split_and_merge
from transfertwin.navigation._robot import RobotConfig

__all__ = ["DockEstimate", "estimate_dock_pose"]


@dataclass(frozen=True)
class DockEstimate:
    """One docking-pose estimate, everything in the robot frame F_D as the robot believes it.

    Attributes:
        edge: Estimated edge frame (3,).
        goal: Estimated docking goal F_D_G (3,).
        line: The chosen line (in F_D).
        lines: All lines of the scan (in F_D).
    """

    edge: np.ndarray
    goal: np.ndarray
    line: LineSegment
    lines: tuple[LineSegment, ...]


def _to_robot(line: LineSegment, mount: np.ndarray) -> LineSegment:
    """A line from the scanner frame into F_D (assumed scanner mounting)."""
    c, s = math.cos(mount[2]), math.sin(mount[2])
    rot = np.array([[c, -s], [s, c]])
    pts = to_world(mount, np.stack([line.start, line.end, line.centroid]))
    return LineSegment(pts[0], pts[1], pts[2], rot @ line.direction, line.n_points, line.rms_m)


def _edge_of(line: LineSegment, expected: np.ndarray, mount: str) -> np.ndarray:
    """The edge frame a line implies: reference end and inward normal (away from the robot)."""
    ey = np.array([-math.sin(expected[2]), math.cos(expected[2])])  # along the face, leftwards
    d = line.direction if line.direction @ ey >= 0 else -line.direction
    lo, hi = sorted((line.start, line.end), key=lambda p: float(p @ ey))
    origin = hi if mount == "left" else lo
    normal = np.array([d[1], -d[0]])  # d rotated by -90°: from the robot into the station
    return np.array([origin[0], origin[1], math.atan2(normal[1], normal[0])])


def estimate_dock_pose(
    scan: Scan,
    station: Station,
    expected_edge: np.ndarray,
    robot: RobotConfig,
    laser: LaserConfig,
    seg: SegmentationConfig,
    gate_m: float = 0.25,
    max_angle_rad: float = math.radians(15.0),
    min_fraction: float = 0.5,
) -> DockEstimate | None:
    """The docking goal from one scan, or None when no line matches the station.

    Args:
        scan: The sweep (scanner frame).
        station: Target station (mount side and goal offset).
        expected_edge: Where map and belief put the edge frame, in F_D (3,).
        robot: The assumed scanner mounting.
        laser: Beam spacing.
        seg: Segmentation thresholds.
        gate_m: Largest distance of the line's reference end from the expected edge, m.
        max_angle_rad: Largest angle between the line and the expected face, rad.
        min_fraction: Shortest line as a fraction of the face's length.
    """
    mount = np.array([*robot.laser_xy_m, robot.laser_yaw_rad])
    raw = split_and_merge(scan.points(), scan.ranges, laser.step_rad, seg)
    lines = tuple(_to_robot(line, mount) for line in raw)
    best, best_dist = None, math.inf
    for line in lines:
        if line.length_m < min_fraction * station.width_m:
            continue
        edge = _edge_of(line, expected_edge, station.mount)
        if abs(wrap_angle(edge[2] - expected_edge[2])) > max_angle_rad:
            continue
        if np.linalg.norm(edge[:2] - expected_edge[:2]) > gate_m:
            continue
        dist = float(np.linalg.norm(line.centroid))
        if dist < best_dist:
            best, best_dist = (line, edge), dist
    if best is None:
        return None
    line, edge = best
    return DockEstimate(edge, compose(edge, np.asarray(station.goal_in_edge)), line, lines)
