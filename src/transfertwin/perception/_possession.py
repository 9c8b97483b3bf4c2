"""Scan results against what the assets say they possess (Sec. 5.5).

Before an OTS is formed, the TM scans its belts and the docked unit's. Each unit's
representation (its asset administration shell) says which objects it possesses and how
large they are; the scan says where boxes are. `match_possessions` pairs the two per unit
with a minimum-cost assignment (Hungarian method, `scipy.optimize.linear_sum_assignment`)
and reports

- matched: a detected box that fits an expected object of the unit it lies on;
- moved: a box that fits an object another unit was expected to hold (the representation
  and the belts disagree about possession, not about existence);
- missing: an expected object no box fits;
- unexpected: a box no expected object fits (an unknown object, or two touching objects
  seen as one box).

A box fits an object when its size agrees within `size_tol_m` and, where the expected
position is known, its centre lies within `position_tol_m` of it. The size is compared
without knowing the yaw: an object of extents (L, W) at yaw θ has the footprint
(L|cos θ| + W|sin θ|, L|sin θ| + W|cos θ|); the distance to a detected footprint is the
smallest over θ (a 0.5° grid), unless the expected yaw is given. That footprint is a box's;
a rounded object's is smaller at a slant (a starter-motor core at 60° covers about 162 × 220
mm, not the 240 × 267 of its yaw-0 box turned), so a `Possession` may carry its real
footprint over yaw (`Possession.footprint_m`, e.g. its hull points' extents turned), which is
then used instead.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass

import numpy as np
from scipy.optimize import linear_sum_assignment

from transfertwin._errors import InputError
from transfertwin.perception._aabb import AABB

__all__ = [
    "Possession",
    "PossessionMatch",
    "PossessionReport",
    "footprint_over_yaw",
    "match_possessions",
    "size_distance",
    "unit_by_gap",
]

_YAWS = np.radians(np.arange(0.0, 90.01, 0.5))  # |cos|, |sin| repeat every 90°
_INFEASIBLE = 1e6


@dataclass(frozen=True)
class Possession:
    """One object a unit's representation says it holds.

    Attributes:
        object_id: The object's id in the representation.
        size_m: Full extents (L, W, H) of its AABB in F_T at yaw 0 on the face it lies on
            (m), e.g. 2 (s_x, s_y, s_z) of a state observed at θ = 0.
        xy_m: Where it should lie (x, y) in F_T (m), or None when unknown.
        theta_rad: Its yaw, or None when unknown (the footprint is then compared over
            all yaws).
        footprint_m: Its footprint's extents (x, y) at n yaws evenly over [0°, 180°)
            (`footprint_over_yaw`), or None: the footprint of its yaw-0 box turned.
    """

    object_id: str
    size_m: tuple[float, float, float]
    xy_m: tuple[float, float] | None = None
    theta_rad: float | None = None
    footprint_m: tuple[tuple[float, float], ...] | None = None

    def __post_init__(self) -> None:
        if len(self.size_m) != 3 or not all(math.isfinite(v) and v > 0 for v in self.size_m):
            raise InputError(f"Possession {self.object_id!r}: size_m must be 3 positive numbers")
        if self.footprint_m is not None and not (
            len(self.footprint_m) > 0
            and all(len(f) == 2 and all(math.isfinite(v) and v > 0 for v in f)
                    for f in self.footprint_m)
        ):  # fmt: skip
            raise InputError(f"Possession {self.object_id!r}: footprint_m must be (x, y) pairs "
                             "of positive numbers")  # fmt: skip


@dataclass(frozen=True)
class PossessionMatch:
    """A detected box paired with an expected object.

    Attributes:
        unit: The unit the box lies on.
        expected_unit: The unit whose representation holds the object (== unit unless the
            match is in `PossessionReport.moved`).
        possession: The expected object.
        box: The detected box.
        size_error_m: `size_distance` of the pair.
        position_error_m: Distance of the box centre from `possession.xy_m` (x-y), or None.
    """

    unit: str
    expected_unit: str
    possession: Possession
    box: AABB
    size_error_m: float
    position_error_m: float | None


@dataclass(frozen=True)
class PossessionReport:
    """What the scan found against what the units say they hold.

    Attributes:
        matched: Boxes on the unit that holds their object.
        moved: Boxes that fit an object held by another unit.
        missing: (unit, object) pairs no box fits.
        unexpected: (unit, box) pairs no object fits.
    """

    matched: tuple[PossessionMatch, ...]
    moved: tuple[PossessionMatch, ...]
    missing: tuple[tuple[str, Possession], ...]
    unexpected: tuple[tuple[str, AABB], ...]

    @property
    def consistent(self) -> bool:
        """True when every expected object was found where expected and nothing else."""
        return not (self.moved or self.missing or self.unexpected)

    def summary(self) -> dict[str, list[str]]:
        """Object ids (matched, moved as 'id: A -> B', missing as 'unit/id') and the
        unexpected boxes' centres, for logs and JSON."""
        return {
            "matched": [m.possession.object_id for m in self.matched],
            "moved": [
                f"{m.possession.object_id}: {m.expected_unit} -> {m.unit}" for m in self.moved
            ],
            "missing": [f"{u}/{p.object_id}" for u, p in self.missing],
            "unexpected": [
                f"{u} @ ({b.centre[0]:.3f}, {b.centre[1]:.3f})" for u, b in self.unexpected
            ],
        }


def footprint_over_yaw(points_xy: np.ndarray, n: int = 180) -> tuple[tuple[float, float], ...]:
    """Extents (x, y) of points (k, 2) turned by n yaws evenly over [0°, 180°), m: a
    `Possession.footprint_m` (the extents repeat every 180°)."""
    pts = np.asarray(points_xy, dtype=float)
    if pts.ndim != 2 or pts.shape[1] != 2 or len(pts) == 0 or n < 1:
        raise InputError("footprint_over_yaw: points must be (k, 2) with k >= 1, n >= 1")
    yaws = np.pi * np.arange(n) / n
    c, s = np.cos(yaws)[:, None], np.sin(yaws)[:, None]
    x = c * pts[:, 0] - s * pts[:, 1]
    y = s * pts[:, 0] + c * pts[:, 1]
    return tuple(zip(np.ptp(x, axis=1).tolist(), np.ptp(y, axis=1).tolist(), strict=True))


def size_distance(box: AABB, size_m: Sequence[float], theta_rad: float | None = None,
                  footprint_m: Sequence[Sequence[float]] | None = None) -> float:  # fmt: skip
    """Largest extent difference (m) between a box and an object of extents (L, W, H),
    at yaw `theta_rad`, or at the yaw that fits best when None; with `footprint_m` (the
    object's footprint over yaw, `Possession.footprint_m`) its footprint is that, not its
    yaw-0 box's turned."""
    dx, dy, dz = (2.0 * h for h in box.half)
    length, width, height = size_m
    if footprint_m is not None:
        fp = np.asarray(footprint_m, dtype=float)
        if theta_rad is not None:
            fp = fp[[round(theta_rad % math.pi / math.pi * len(fp)) % len(fp)]]
        foot = np.maximum(np.abs(dx - fp[:, 0]), np.abs(dy - fp[:, 1]))
        return float(max(foot.min(), abs(dz - height)))
    yaws = _YAWS if theta_rad is None else np.array([theta_rad])
    c, s = np.abs(np.cos(yaws)), np.abs(np.sin(yaws))
    foot = np.maximum(np.abs(dx - (length * c + width * s)), np.abs(dy - (length * s + width * c)))
    return float(max(foot.min(), abs(dz - height)))


def unit_by_gap(gap_m: float, near: str = "TM", far: str = "TU") -> Callable[[AABB], str]:
    """The unit a box lies on by its centre x: `near` up to the middle of the gap, then
    `far` (the rule `PerceptionSensor` uses for possession)."""
    return lambda box: near if box.centre[0] <= 0.5 * gap_m else far


def _cost(
    boxes: Sequence[AABB], items: Sequence[Possession], size_tol: float, pos_tol: float
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Assignment cost (boxes x items), size and position errors (NaN: position unknown)."""
    n, m = len(boxes), len(items)
    size = np.empty((n, m))
    pos = np.full((n, m), np.nan)
    for i, box in enumerate(boxes):
        for j, p in enumerate(items):
            size[i, j] = size_distance(box, p.size_m, p.theta_rad, p.footprint_m)
            if p.xy_m is not None:
                pos[i, j] = math.dist(box.centre[:2], p.xy_m)
    cost = size / size_tol + np.nan_to_num(pos / pos_tol, nan=0.0)
    cost[(size > size_tol) | (pos > pos_tol)] = _INFEASIBLE
    return cost, size, pos


def _assign(
    boxes: Sequence[AABB],
    items: Sequence[Possession],
    size_tol: float,
    pos_tol: float,
    barred: np.ndarray | None = None,
) -> list[tuple[int, int, float, float | None]]:
    """Feasible pairs (box index, item index, size error, position error); `barred`
    (boxes x items) marks pairs that may not match."""
    if not boxes or not items:
        return []
    cost, size, pos = _cost(boxes, items, size_tol, pos_tol)
    if barred is not None:
        cost[barred] = _INFEASIBLE
    rows, cols = linear_sum_assignment(cost)
    return [
        (int(i), int(j), float(size[i, j]), None if math.isnan(pos[i, j]) else float(pos[i, j]))
        for i, j in zip(rows, cols, strict=True)
        if cost[i, j] < _INFEASIBLE
    ]


def match_possessions(
    boxes: Sequence[AABB],
    expected: Mapping[str, Sequence[Possession]],
    unit_of: Callable[[AABB], str],
    *,
    size_tol_m: float = 0.025,
    position_tol_m: float = 0.08,
) -> PossessionReport:
    """Match a scan's boxes with the units' expected possessions.

    First per unit (boxes on a unit against that unit's objects), then the leftovers across
    units (a box on one unit that fits an object another unit holds: `moved`).

    Args:
        boxes: The scan's detections in F_T (`workspace_scan(...)[0].boxes`).
        expected: Unit name → the objects its representation says it holds.
        unit_of: The unit a box lies on (`unit_by_gap(scene.gap_m)` for TM and TU); a name
            not in `expected` holds nothing.
        size_tol_m: Largest `size_distance` of a match (default 25 mm: the detector's
            face error on cores reaches 10–15 mm at p95, docs/perception.md).
        position_tol_m: Largest x-y distance of a match from a known expected position.

    Raises:
        InputError: On non-positive tolerances or an object id expected twice.
    """
    if not (size_tol_m > 0 and position_tol_m > 0):
        raise InputError("match_possessions: tolerances must be positive")
    ids = [p.object_id for items in expected.values() for p in items]
    if len(set(ids)) != len(ids):
        raise InputError("match_possessions: an object id is expected more than once")
    units = list(expected) + sorted({unit_of(b) for b in boxes} - set(expected))
    left_boxes: dict[str, list[AABB]] = {u: [b for b in boxes if unit_of(b) == u] for u in units}
    left_items: dict[str, list[Possession]] = {u: list(expected.get(u, ())) for u in units}
    matched: list[PossessionMatch] = []
    for unit in units:
        bs, items = left_boxes[unit], left_items[unit]
        pairs = _assign(bs, items, size_tol_m, position_tol_m)
        matched += [PossessionMatch(unit, unit, items[j], bs[i], se, pe) for i, j, se, pe in pairs]
        left_boxes[unit] = [b for i, b in enumerate(bs) if i not in {p[0] for p in pairs}]
        left_items[unit] = [p for j, p in enumerate(items) if j not in {q[1] for q in pairs}]
    # leftovers across units, by size only (the expected position was on the other unit)
    rest_boxes = [(u, b) for u in units for b in left_boxes[u]]
    rest_items = [(u, p) for u in units for p in left_items[u]]
    loose = [Possession(p.object_id, p.size_m, None, p.theta_rad, p.footprint_m)
             for _, p in rest_items]
    same = np.array([[ub == ui for ui, _ in rest_items] for ub, _ in rest_boxes], dtype=bool)
    pairs = _assign([b for _, b in rest_boxes], loose, size_tol_m, position_tol_m, same)
    moved = [
        PossessionMatch(rest_boxes[i][0], rest_items[j][0], rest_items[j][1], rest_boxes[i][1],
                        se, None)
        for i, j, se, _ in pairs
    ]  # fmt: skip
    used_b, used_i = {q[0] for q in pairs}, {q[1] for q in pairs}
    return PossessionReport(
        matched=tuple(matched),
        moved=tuple(moved),
        missing=tuple(x for j, x in enumerate(rest_items) if j not in used_i),
        unexpected=tuple(x for i, x in enumerate(rest_boxes) if i not in used_b),
    )
