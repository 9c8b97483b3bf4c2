"""The shop floor: walls, obstacles and four station modules A–D; its occupancy grid
(Sec. 5.4.1, Fig. 5.10a).

A station module is a cuboid whose *front face* looks into the aisle. Its transfer unit sits
at the face's *left* or *right* mounting position (Fig. 5.16): the docked transport module
then lines up either its left side (where the laser scanner is) or its right side with the
face's outer edge on that side. The docking-pose estimator uses that outer edge, so the
mounting decides how far the edge is from the scanner.

Frames: the world is x right, y up (m). A station's *edge frame* sits on the reference outer
edge of its front face, x along the face's inward normal (the direction a docked robot looks),
y along the face to the left as the docked robot sees it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cached_property

import numpy as np

from transfertwin._errors import InputError
from transfertwin.navigation._geometry import Rect, compose

__all__ = ["MOUNTS", "STATION_NAMES", "ShopFloor", "Station", "default_floor"]

#: Mounting positions of a transfer unit on a station module's front face.
MOUNTS = ("left", "right")
#: The study's four stations.
STATION_NAMES = ("A", "B", "C", "D")


@dataclass(frozen=True)
class Station:
    """A station module with its transfer unit.

    Attributes:
        name: 'A'..'D'; the transfer unit is 'TU_' + name.
        face_x_m, face_y_m: Centre of the front face in the world, m.
        yaw_rad: Direction of the face's inward normal (the docked robot's heading), rad.
        mount: 'left' or 'right' mounting position of the transfer unit (Fig. 5.16).
        width_m: Length of the front face, m.
        depth_m: Depth of the cuboid behind the face, m.
        goal_in_edge: Goal pose of the robot centre F_D_G in the edge frame (x, y, θ),
            m and rad; set by `default_floor` from the robot's dimensions.
    """

    name: str
    face_x_m: float
    face_y_m: float
    yaw_rad: float
    mount: str
    width_m: float = 1.2
    depth_m: float = 0.8
    goal_in_edge: tuple[float, float, float] = (-0.52, -0.22, 0.0)

    def __post_init__(self) -> None:
        if self.mount not in MOUNTS:
            raise InputError(f"station {self.name}: mount must be one of {MOUNTS}")

    @property
    def transfer_unit(self) -> str:
        """The transfer unit's name as in the real tables ('TU_A')."""
        return f"TU_{self.name}"

    @property
    def face_pose(self) -> np.ndarray:
        """Front-face centre frame (x along the inward normal), shape (3,)."""
        return np.array([self.face_x_m, self.face_y_m, self.yaw_rad])

    @property
    def edge_pose(self) -> np.ndarray:
        """The reference outer edge frame in the world, shape (3,)."""
        side = 1.0 if self.mount == "left" else -1.0
        return compose(self.face_pose, np.array([0.0, side * self.width_m / 2.0, 0.0]))

    @property
    def rect(self) -> Rect:
        """The cuboid's footprint."""
        c = compose(self.face_pose, np.array([self.depth_m / 2.0, 0.0, 0.0]))
        return Rect(c[0], c[1], self.depth_m, self.width_m, self.yaw_rad, self.name)

    def goal_pose(self) -> np.ndarray:
        """The true docking goal F_D_G in the world, shape (3,)."""
        return compose(self.edge_pose, np.asarray(self.goal_in_edge))

    def coarse_pose(self, distance_m: float) -> np.ndarray:
        """The global planner's target: the goal backed off by `distance_m` along −x."""
        return compose(self.goal_pose(), np.array([-distance_m, 0.0, 0.0]))


@dataclass(frozen=True)
class ShopFloor:
    """Walls, obstacles and stations, and the occupancy grid rasterised from them.

    Attributes:
        size_m: (width, height) of the floor, m.
        obstacles: Solid rectangles other than stations (walls, pillars, racks).
        stations: The station modules.
        resolution_m: Occupancy-grid cell size, m.
    """

    size_m: tuple[float, float]
    obstacles: tuple[Rect, ...]
    stations: tuple[Station, ...]
    resolution_m: float = 0.05

    def station(self, name: str) -> Station:
        """The station called `name` ('A'..'D')."""
        for s in self.stations:
            if s.name == name:
                return s
        raise InputError(f"unknown station {name!r}: expected one of {self.station_names}")

    @property
    def station_names(self) -> tuple[str, ...]:
        """Names of the stations in floor order."""
        return tuple(s.name for s in self.stations)

    @property
    def solids(self) -> tuple[Rect, ...]:
        """Everything the laser sees and the robot must not hit."""
        return self.obstacles + tuple(s.rect for s in self.stations)

    @cached_property
    def segments(self) -> np.ndarray:
        """All solid edges (S, 2, 2) for ray casting, m."""
        return np.concatenate([r.segments() for r in self.solids])

    @cached_property
    def grid(self) -> np.ndarray:
        """Occupancy grid (H, W) bool, row i at y = (i + ½)·res, column j at x = (j + ½)·res."""
        w = round(self.size_m[0] / self.resolution_m)
        h = round(self.size_m[1] / self.resolution_m)
        xs = (np.arange(w) + 0.5) * self.resolution_m
        ys = (np.arange(h) + 0.5) * self.resolution_m
        pts = np.stack(np.meshgrid(xs, ys), axis=-1).reshape(-1, 2)
        occ = np.zeros(len(pts), dtype=bool)
        for r in self.solids:
            occ |= r.contains(pts)
        return occ.reshape(h, w)

    @cached_property
    def clearance(self) -> np.ndarray:
        """Distance (H, W) from each cell centre to the nearest occupied cell, m (less half a
        cell, so that it bounds the distance to the solid from below)."""
        from scipy import ndimage  # here: a unit that asks only for its docking goal skips it

        d = ndimage.distance_transform_edt(~self.grid) * self.resolution_m
        return np.maximum(d - self.resolution_m / 2.0, 0.0)

    def clearance_at(self, points: np.ndarray) -> np.ndarray:
        """Clearance (N,) at world points (N, 2), m (nearest cell; 0 off the floor)."""
        p = np.atleast_2d(points)
        j = np.floor(p[:, 0] / self.resolution_m).astype(int)
        i = np.floor(p[:, 1] / self.resolution_m).astype(int)
        h, w = self.grid.shape
        inside = (i >= 0) & (i < h) & (j >= 0) & (j < w)
        out = np.zeros(len(p))
        out[inside] = self.clearance[i[inside], j[inside]]
        return out


def _wall(x0: float, y0: float, x1: float, y1: float) -> Rect:
    return Rect((x0 + x1) / 2, (y0 + y1) / 2, x1 - x0, y1 - y0, 0.0, "wall")


def default_floor(
    laser_xy_m: tuple[float, float] = (0.37, 0.22), standoff_m: float = 0.15
) -> ShopFloor:
    """The demonstration shop floor (12 m × 8 m, four stations, three obstacles).

    A and D carry their transfer unit at the left mounting position, B and C at the right
    one (the study does not say which; this matches its finding that A and D dock more
    accurately in y, Sec. 6.3, and Sec. 5.5's explanation of it).

    Args:
        laser_xy_m: The scanner's position in the robot centre frame F_D, m; the goal puts
            the scanner (left mount) or the robot's right front corner (right mount) in line
            with the reference edge.
        standoff_m: Distance from the robot's front to the station face when docked, m (the
            transfer unit's belts overhang the cuboid by about this much).
    """
    lx, ly = laser_xy_m
    gx = -(standoff_m + lx)
    goal = {"left": (gx, -ly, 0.0), "right": (gx, ly, 0.0)}
    half_pi = math.pi / 2
    specs = (
        ("A", 2.6, 6.6, half_pi, "left"),
        ("B", 7.6, 6.6, half_pi, "right"),
        ("C", 9.4, 1.4, -half_pi, "right"),
        ("D", 4.2, 1.4, -half_pi, "left"),
    )
    stations = tuple(Station(n, x, y, a, m, goal_in_edge=goal[m]) for n, x, y, a, m in specs)
    t = 0.1
    walls = (
        _wall(0.0, 0.0, 12.0, t),
        _wall(0.0, 8.0 - t, 12.0, 8.0),
        _wall(0.0, 0.0, t, 8.0),
        _wall(12.0 - t, 0.0, 12.0, 8.0),
    )
    others = (
        Rect(6.0, 4.0, 0.4, 0.4, 0.0, "pillar"),
        Rect(2.2, 3.8, 1.6, 0.6, 0.0, "rack"),
        Rect(10.2, 4.6, 0.6, 1.4, 0.3, "cart"),
    )
    return ShopFloor((12.0, 8.0), walls + others, stations)
