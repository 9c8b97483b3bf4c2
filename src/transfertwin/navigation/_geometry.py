"""Planar rigid transforms SE(2) and axis-aligned-or-rotated rectangles (the floor's solids).

A pose (x, y, θ) in metres and radians is the frame of a body in the world: a point p in the
body frame is R(θ) p + (x, y) in the world. Poses are plain numpy arrays of shape (3,) so
that batches (N, 3) stay vectorised.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

__all__ = ["Rect", "compose", "invert", "relative", "to_world", "wrap_angle"]


def wrap_angle(a: float | np.ndarray) -> float | np.ndarray:
    """Angle(s) wrapped to [-π, π)."""
    return (np.asarray(a) + math.pi) % (2.0 * math.pi) - math.pi


def compose(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """a ∘ b: the pose b (given in frame a) in the world, shape (3,)."""
    c, s = math.cos(a[2]), math.sin(a[2])
    return np.array(
        [a[0] + c * b[0] - s * b[1], a[1] + s * b[0] + c * b[1], wrap_angle(a[2] + b[2])]
    )


def invert(a: np.ndarray) -> np.ndarray:
    """a⁻¹, shape (3,)."""
    c, s = math.cos(a[2]), math.sin(a[2])
    return np.array([-c * a[0] - s * a[1], s * a[0] - c * a[1], wrap_angle(-a[2])])


def relative(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """a⁻¹ ∘ b: the pose b seen from frame a, shape (3,)."""
    return compose(invert(a), b)


def to_world(pose: np.ndarray, points: np.ndarray) -> np.ndarray:
    """Points (N, 2) in the frame `pose` → world (N, 2)."""
    c, s = math.cos(pose[2]), math.sin(pose[2])
    rot = np.array([[c, -s], [s, c]])
    return np.asarray(points, dtype=float) @ rot.T + pose[:2]


@dataclass(frozen=True)
class Rect:
    """A solid rectangle on the floor (wall, pillar, station cuboid's footprint).

    Attributes:
        cx_m, cy_m: Centre in the world, m.
        length_m: Extent along the rectangle's own x axis, m.
        width_m: Extent along its y axis, m.
        yaw_rad: Rotation of its x axis from the world's x axis, rad.
        name: Label (station name, 'wall', ...).
    """

    cx_m: float
    cy_m: float
    length_m: float
    width_m: float
    yaw_rad: float = 0.0
    name: str = ""

    @property
    def pose(self) -> np.ndarray:
        """Centre frame (x, y, θ)."""
        return np.array([self.cx_m, self.cy_m, self.yaw_rad])

    def corners(self) -> np.ndarray:
        """Corners (4, 2) counter-clockwise, starting at (-l/2, -w/2) in the own frame."""
        hl, hw = self.length_m / 2.0, self.width_m / 2.0
        local = np.array([[-hl, -hw], [hl, -hw], [hl, hw], [-hl, hw]])
        return to_world(self.pose, local)

    def segments(self) -> np.ndarray:
        """The four edges as (4, 2, 2): segment i runs from corner i to corner i+1."""
        c = self.corners()
        return np.stack([c, np.roll(c, -1, axis=0)], axis=1)

    def contains(self, points: np.ndarray) -> np.ndarray:
        """(N,) bool: which points (N, 2) lie inside (boundary included)."""
        p = np.atleast_2d(points) - np.array([self.cx_m, self.cy_m])
        c, s = math.cos(self.yaw_rad), math.sin(self.yaw_rad)
        u = p[:, 0] * c + p[:, 1] * s
        v = -p[:, 0] * s + p[:, 1] * c
        return (np.abs(u) <= self.length_m / 2.0) & (np.abs(v) <= self.width_m / 2.0)
