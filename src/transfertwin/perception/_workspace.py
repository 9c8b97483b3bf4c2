"""The OTS workspace: where the detector expects objects (Sec. 5.4.3).

Undocked, the workspace is the space above the TM's two belts; docked, the docked unit's
belts are added. The robot does not know its docking error, so the docked unit's belts are
placed where a perfect docking would put them (the nominal gap, no offset, no yaw); the
margin absorbs the error. Each belt pair is one box in F_T: x along the unit's belts, y
across both belts plus the margin, z from just below the belt surface (cutting off the
rounded pulley ends, whose points the plane fit would not remove) to `height_m`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from transfertwin.sim import LayoutConfig

__all__ = ["Workspace"]


@dataclass(frozen=True)
class Workspace:
    """Axis-aligned boxes in F_T, each (lo (3,), hi (3,)) in metres."""

    boxes: tuple[tuple[tuple[float, float, float], tuple[float, float, float]], ...]

    @classmethod
    def for_layout(
        cls,
        layout: LayoutConfig,
        gap_m: float,
        *,
        docked: bool = True,
        margin_m: float = 0.03,
        z_low_m: float = -0.003,
        height_m: float = 0.35,
    ) -> Workspace:
        """The TM's belts, and the docked unit's at the nominal gap when `docked`."""
        y = 0.5 * layout.belt_separation_m + layout.belt_width_m + margin_m
        tm = ((-layout.tm_length_m - margin_m, -y, z_low_m), (margin_m, y, height_m))
        boxes = [tm]
        if docked:
            x0 = gap_m - margin_m
            boxes.append(((x0, -y, z_low_m), (gap_m + layout.tu_length_m + margin_m, y, height_m)))
        return cls(tuple(boxes))

    def contains(self, points: np.ndarray) -> np.ndarray:
        """(n,) bool: which points (n, 3) in F_T lie in some box."""
        pts = np.asarray(points, dtype=float)
        inside = np.zeros(len(pts), dtype=bool)
        for lo, hi in self.boxes:
            inside |= np.all((pts >= lo) & (pts <= hi), axis=1)
        return inside
