"""The transport module's depth camera in the loop (docs/architecture.md,
"Operation"): before an OTS is formed, what the camera sees of the module's belts and the
docked unit's is matched with what the ledger says each holds (`match_possessions`,
Sec. 5.5); an object missing, seen on the other unit, or a box nobody expects stops the
step with the reason, which goes into the order's history.

What the ledger says an object is comes from its model: the extents of its convex hulls
lying on the face it was loaded on, their footprint at every yaw (`expected_footprint`: a
core is rounded, so at 60° it covers about 162 × 220 mm, where its yaw-0 box turned would
cover 240 × 267), compared over every yaw (the camera's AABB cannot tell the yaw).

The camera looks from the module across the gap, low over the belts, so on the docked unit
the far end of an object can hide behind its own taller near part (measured: o9 in the
middle of the unit's belts is seen 174 of 218 mm long, its far end 46 mm short; a servoed
look at it, Eq. 5.14, sees no more). A box on the unit is therefore read as a lower bound of
the length away from the camera (`far_side_open`): when it is shorter along x than the
expected object at the yaw that fits its width, its far end is taken as hidden by up to
`OCCLUSION_M`, and it is matched on its width and height.

The model's height is the extent it gets most wrong: a real core rests on features its mesh
lacks (measured on the emulated plant of seed 7: o10 stands 116 mm high on its front face,
its model 85 mm; o19 124 mm against 89), and the camera sees its top. So the module learns
how high each object stands on each face, as the floor learns its transfers: when the scan
and the ledger disagree only in that the object the ledger has there is seen with the right
footprint but another height (within `HEIGHT_SLACK_M`), and nothing else is on either side,
the box is taken as that object, the height it was seen with is learnt for (object, face)
and said in the order's history; from then on that height is the expectation, matched at the
usual tolerance, and a box that disagrees with it stops the step like any other. What the
camera checks is presence and count where the ledger says, and shape within the tolerance:
among cores of similar size it cannot tell one from another, and does not pretend to.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from functools import lru_cache
from typing import NamedTuple

import numpy as np

from transfertwin.perception import (
    AABB,
    Possession,
    footprint_over_yaw,
    match_possessions,
    size_distance,
    unit_by_gap,
)

__all__ = [
    "HEIGHT_SLACK_M",
    "OCCLUSION_M",
    "SIZE_TOL_M",
    "ScanVerdict",
    "expected_footprint",
    "expected_size",
    "far_side_open",
    "height_key",
    "scan_check",
]

#: How much of an object's far end on the docked unit the camera may not see, m.
OCCLUSION_M = 0.06
#: How far a box's extents may differ from the expected object's (`match_possessions`'
#: default: the detector's face error on cores reaches 10–15 mm at p95), m.
SIZE_TOL_M = 0.025
#: How far the height seen the first time may differ from the model's before the box is not
#: taken as the object (a third of a core's height; the plant's largest difference is 40 mm).
HEIGHT_SLACK_M = 0.05


class ScanVerdict(NamedTuple):
    """A scan against the ledger.

    Attributes:
        ok: The scan agrees with the ledger.
        why: The reason when not ('' when it does).
        summary: `PossessionReport.summary()` of the match, plus 'learnt' (what was learnt).
        height_m: The height the object was seen with when it was learnt by this scan
            (None: nothing learnt).
    """

    ok: bool
    why: str
    summary: dict[str, list[str]]
    height_m: float | None = None


def height_key(obj: str, face: str) -> str:
    """The key of a learnt height: 'o10/front'."""
    return f"{obj}/{face}"


@lru_cache(maxsize=256)
def _lying(obj: str, face: str) -> np.ndarray:
    """`obj`'s hull points lying on `face` at yaw 0 (n, 3), m."""
    import mujoco

    from transfertwin.objects import load_object
    from transfertwin.sim import object_quat

    pts = np.vstack(load_object(obj).hulls)
    rot = np.empty(9)
    mujoco.mju_quat2Mat(rot, object_quat(face, 0.0))
    return pts @ rot.reshape(3, 3).T


def expected_size(obj: str, face: str) -> tuple[float, float, float]:
    """Full extents (L, W, H) of `obj`'s hulls lying on `face` at yaw 0, m."""
    ext = np.ptp(_lying(obj, face), axis=0)
    return (float(ext[0]), float(ext[1]), float(ext[2]))


@lru_cache(maxsize=256)
def expected_footprint(obj: str, face: str) -> tuple[tuple[float, float], ...]:
    """Extents (x, y) of `obj`'s footprint lying on `face` at each whole degree of yaw
    0..179 (`perception.footprint_over_yaw` of its hull points), m."""
    return footprint_over_yaw(_lying(obj, face)[:, :2], 180)


def far_side_open(box: AABB, footprint: Sequence[Sequence[float]]) -> AABB:
    """`box` with its far end (+x, away from the module's camera) extended to the length the
    expected object of footprint `footprint` (`expected_footprint`) has at the yaw that fits
    the box's width, by at most `OCCLUSION_M`; unchanged when it is that long already."""
    fp = np.asarray(footprint, dtype=float)
    best = int(np.argmin(np.abs(2.0 * box.half[1] - fp[:, 1])))
    missing = fp[best, 0] - 2.0 * box.half[0]
    if missing <= 0.0:
        return box
    grow = min(missing, OCCLUSION_M)
    near = box.centre[0] - box.half[0]
    half_x = box.half[0] + 0.5 * grow
    return AABB((near + half_x, box.centre[1], box.centre[2]), (half_x, box.half[1], box.half[2]))


def scan_check(boxes: Sequence[AABB], obj: str, face: str, tm: str, unit: str, pickup: bool,
               gap_m: float, heights: Mapping[str, float] | None = None,
               ) -> ScanVerdict:  # fmt: skip
    """Match the scan with the ledger: `obj` on `unit` before a pick-up, on the module
    `tm` before a delivery, nothing else on either. `heights` holds the heights learnt
    so far (`height_key` -> m); without one for (obj, face) the model's height is expected
    and a box that differs from it only in height, by at most `HEIGHT_SLACK_M`, is taken
    as the object and its height learnt (module docstring)."""
    holder = unit if pickup else tm
    size, footprint = expected_size(obj, face), expected_footprint(obj, face)
    learnt = (heights or {}).get(height_key(obj, face))
    if learnt is not None:
        size = (size[0], size[1], float(learnt))
    on = unit_by_gap(gap_m, tm, unit)
    seen = {}  # what the camera saw, by the box that is matched
    for box in boxes:
        opened = far_side_open(box, footprint) if on(box) == unit else box
        seen[id(opened)] = (opened, box)
    expected = {tm: [], unit: [], holder: [Possession(obj, size, footprint_m=footprint)]}
    report = match_possessions([o for o, _ in seen.values()], expected, on,
                               size_tol_m=SIZE_TOL_M)  # fmt: skip
    summary = report.summary()
    if report.consistent:
        return ScanVerdict(True, "", summary)
    if learnt is None and len(report.missing) == 1 and not report.moved \
            and [u for u, _ in report.unexpected] == [holder]:  # fmt: skip
        box = report.unexpected[0][1]
        height = 2.0 * box.half[2]
        flat = AABB(box.centre, (*box.half[:2], 0.5 * size[2]))  # the footprint alone
        if size_distance(flat, size, None, footprint) <= SIZE_TOL_M \
                and abs(height - size[2]) <= HEIGHT_SLACK_M:  # fmt: skip
            summary = {**summary, "matched": [obj], "missing": [], "unexpected": [],
                       "learnt": [f"{obj} stands {1000 * height:.0f} mm high on its {face} "
                                  f"face (its model {1000 * size[2]:.0f} mm)"]}  # fmt: skip
            return ScanVerdict(True, "", summary, height)
    why = []
    for where, p in report.missing:
        why.append(f"{p.object_id} not seen on {where}")
    for m in report.moved:
        why.append(f"{m.possession.object_id} seen on {m.unit}, not on {m.expected_unit}")
    for where, box in report.unexpected:
        dims = " x ".join(f"{2000 * v:.0f}" for v in seen[id(box)][1].half[:2])
        why.append(f"an unexpected object ({dims} mm) on {where}")
    return ScanVerdict(False, "the camera disagrees with the ledger: " + "; ".join(why), summary)
