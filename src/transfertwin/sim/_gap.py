"""Top-view gap area between the docked belts (Sec. 5.5, Fig. 5.18; data column gap_area_cm2).

Pure geometry, no MuJoCo. The gap in the top view is the strip between the TM's tip line
(x = 0 in F_T) and the TU's near end line, which the docking error ξ shifts and turns
(Eq. 6.11, `tu_pose_in_tip_frame`). Its width at a lateral position y is

    g(y) = x_TU(y) = tx - tan(ψ) · (y - ty),      (tx, ty, ψ) = TU pose in F_T,

and the gap area over a conveyor is the integral of g over the conveyor's corridor
[y0, y1] (linear in y, so integrated exactly).

What the real `gap_area_cm2` column is (a least-squares fit on the 191 rows;
`benchmarks/fidelity.py` prints it):

- the *excess* area caused by the docking error, i.e. measured from the goal line
  (nominal gap 0 in this formula; the fitted offset is 0.1 mm),
- taken as an absolute value of the signed area (a TM that overshoots gives a positive
  number, like a shoelace polygon area that was abs'ed),
- over a corridor about 245 mm wide centred on the conveyor in use: the left belt
  (centre ≈ +117 mm), the right belt (≈ -137 mm) or, for 'both', the centre line
  (≈ -10 mm with F_D 0.40 m behind the tip), so the yaw error's lever differs by conveyor.

`gap_area_m2` implements that definition with layout values as parameters; the defaults
of `GapAreaLayout.fitted()` reproduce the data (R² ≈ 0.999, bias ≈ 0).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from transfertwin.sim._config import DockingError, LayoutConfig
from transfertwin.sim._docking import tu_pose_in_tip_frame

__all__ = ["GapAreaLayout", "conveyor_span", "gap_area_m2", "gap_areas_cm2", "gap_width_m"]


@dataclass(frozen=True)
class GapAreaLayout:
    """The geometric quantities the gap area depends on (m).

    Attributes:
        gap_m: Gap at zero docking error (d_gap; 0 gives the *excess* area the data hold).
        corridor_width_m: Width of the strip the area is taken over (one belt's width).
        corridor_centre_m: |y| of the left/right corridor's centre line (F_T, before the
            pivot shift); 'both' is centred at y = 0.
        pivot_y_m: Lateral offset of the whole belt layout relative to F_D's x axis (the
            axis the docking error's yaw turns about).
        tip_to_centre_m: Distance of F_D behind the tip.
        absolute: Take |signed area| (the data's convention) instead of the signed value.
    """

    gap_m: float = 0.0
    corridor_width_m: float = 0.195
    corridor_centre_m: float = 0.1025
    pivot_y_m: float = 0.0
    tip_to_centre_m: float = 0.40
    absolute: bool = True

    @classmethod
    def from_layout(cls, layout: LayoutConfig, gap_m: float = 0.0) -> GapAreaLayout:
        """The scene's own geometry (belt width, belt centre, F_D distance)."""
        return cls(
            gap_m=gap_m,
            corridor_width_m=layout.belt_width_m,
            corridor_centre_m=layout.belt_centre_y("left"),
            tip_to_centre_m=layout.tip_to_centre_m,
        )

    @classmethod
    def fitted(cls) -> GapAreaLayout:
        """Least-squares fit to the 191 real rows (R² 0.999; see `benchmarks/fidelity.py`)."""
        return cls(
            gap_m=0.0002,
            corridor_width_m=0.2458,
            corridor_centre_m=0.1269,
            pivot_y_m=-0.0098,
            tip_to_centre_m=0.40,
        )


def conveyor_span(geo: GapAreaLayout, conveyor: str) -> tuple[float, float]:
    """Corridor [y0, y1] in F_T (m) for conveyor 'left', 'right' or 'both'."""
    half = 0.5 * geo.corridor_width_m
    centre = {"left": geo.corridor_centre_m, "right": -geo.corridor_centre_m, "both": 0.0}
    if conveyor not in centre:
        raise ValueError(f"conveyor must be left, right or both, got {conveyor!r}")
    c = centre[conveyor] + geo.pivot_y_m
    return c - half, c + half


def gap_width_m(geo: GapAreaLayout, error: DockingError, y_m: np.ndarray) -> np.ndarray:
    """Gap width g(y) (m) in x between the TM tip line and the TU's near end line."""
    tx, ty, psi = tu_pose_in_tip_frame(error, geo.gap_m, geo.tip_to_centre_m)
    return tx - np.tan(psi) * (np.asarray(y_m, dtype=float) - ty)


def gap_area_m2(geo: GapAreaLayout, error: DockingError, conveyor: str) -> float:
    """Top-view gap area (m²) over the conveyor's corridor (see the module docstring)."""
    y0, y1 = conveyor_span(geo, conveyor)
    tx, ty, psi = tu_pose_in_tip_frame(error, geo.gap_m, geo.tip_to_centre_m)
    t = float(np.tan(psi))
    signed = (tx + t * ty) * (y1 - y0) - 0.5 * t * (y1 * y1 - y0 * y0)
    return abs(signed) if geo.absolute else signed


def gap_areas_cm2(
    geo: GapAreaLayout, errors_mm_deg: np.ndarray, conveyors: Sequence[str]
) -> np.ndarray:
    """`gap_area_m2` in cm² for many docking errors (n, 3: mm, mm, deg) and conveyors (n,)."""
    return np.array([
        gap_area_m2(geo, DockingError.from_mm_deg(*map(float, e)), str(c)) * 1e4
        for e, c in zip(np.asarray(errors_mm_deg, dtype=float), conveyors, strict=True)
    ])  # fmt: skip
