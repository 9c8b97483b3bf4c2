"""Axis-aligned bounding boxes in F_T (Fig. 5.11b): centre (x, y, z) and half extents."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from transfertwin.sim import VirtualTransferSystem

__all__ = ["AABB", "ground_truth_aabb"]


@dataclass(frozen=True)
class AABB:
    """An AABB in F_T: centre (x, y, z) and half extents (s_x, s_y, s_z), metres (Eq. 5.4).

    Attributes:
        centre: (3,) centre.
        half: (3,) half extents (>= 0).
        n_points: Points of the cluster it bounds (0 for a ground truth).
    """

    centre: tuple[float, float, float]
    half: tuple[float, float, float]
    n_points: int = 0

    @classmethod
    def of_points(cls, points: np.ndarray, floor_z: float | None = None) -> AABB:
        """The AABB of points (n, 3); with `floor_z`, extended down to that height."""
        lo, hi = points.min(axis=0), points.max(axis=0)
        if floor_z is not None:
            lo[2] = min(lo[2], floor_z)
        return cls(tuple(map(float, 0.5 * (lo + hi))), tuple(map(float, 0.5 * (hi - lo))),
                   len(points))  # fmt: skip

    @property
    def lo(self) -> np.ndarray:
        """(3,) lower corner."""
        return np.asarray(self.centre) - np.asarray(self.half)

    @property
    def hi(self) -> np.ndarray:
        """(3,) upper corner."""
        return np.asarray(self.centre) + np.asarray(self.half)

    def corner_error(self, other: AABB) -> float:
        """Largest distance (m) between corresponding faces of the two boxes."""
        return float(max(np.abs(self.lo - other.lo).max(), np.abs(self.hi - other.hi).max()))

    def as_dict(self) -> dict[str, float | int]:
        """x, y, z, s_x, s_y, s_z (m) and the point count, for JSON."""
        keys = ("x", "y", "z", "s_x", "s_y", "s_z")
        out: dict[str, float | int] = {
            k: round(v, 5) for k, v in zip(keys, (*self.centre, *self.half), strict=True)
        }
        out["n_points"] = self.n_points
        return out


def ground_truth_aabb(system: VirtualTransferSystem) -> AABB:
    """The object's true AABB in F_T, from its convex hulls' vertices in the scene."""
    state = system.observe()
    return AABB(tuple(map(float, state[1:4])), tuple(map(float, state[4:7])))
