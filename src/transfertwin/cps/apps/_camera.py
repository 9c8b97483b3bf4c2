"""The transport module's depth camera in the loop (issue 28, item 3; docs/architecture.md,
"Operation"): before an OTS is formed, what the camera sees of the module's belts and the
docked unit's is matched with what the ledger says each holds (`match_possessions`,
Sec. 5.5); an object missing, seen on the other unit, or a box nobody expects stops the
step with the reason, which goes into the order's history.

What the ledger says an object is comes from its model: the extents of its convex hulls
lying on the face it was loaded on (yaw 0), compared over every yaw (the camera's AABB
cannot tell the yaw).

The camera looks from the module across the gap, low over the belts, so on the docked unit
the far end of an object can hide behind its own taller near part (measured: o9 in the
middle of the unit's belts is seen 174 of 218 mm long, its far end 46 mm short; a servoed
look at it, Eq. 5.14, sees no more). A box on the unit is therefore read as a lower bound of
the length away from the camera (`far_side_open`): when it is shorter along x than the
expected object at the yaw that fits its width, its far end is taken as hidden by up to
`OCCLUSION_M`, and it is matched on its width and height.
"""

from __future__ import annotations

from collections.abc import Sequence
from functools import lru_cache

import numpy as np

from transfertwin.perception import AABB, Possession, match_possessions, unit_by_gap

__all__ = ["OCCLUSION_M", "expected_size", "far_side_open", "scan_check"]

#: How much of an object's far end on the docked unit the camera may not see, m.
OCCLUSION_M = 0.06


@lru_cache(maxsize=256)
def expected_size(obj: str, face: str) -> tuple[float, float, float]:
    """Full extents (L, W, H) of `obj`'s hulls lying on `face` at yaw 0, m."""
    import mujoco

    from transfertwin.objects import load_object
    from transfertwin.sim import object_quat

    pts = np.vstack(load_object(obj).hulls)
    rot = np.empty(9)
    mujoco.mju_quat2Mat(rot, object_quat(face, 0.0))
    ext = np.ptp(pts @ rot.reshape(3, 3).T, axis=0)
    return (float(ext[0]), float(ext[1]), float(ext[2]))


def far_side_open(box: AABB, size: tuple[float, float, float]) -> AABB:
    """`box` with its far end (+x, away from the module's camera) extended to the length the
    expected object of extents `size` has at the yaw that fits the box's width, by at most
    `OCCLUSION_M`; unchanged when it is that long already."""
    length, width, _ = size
    yaws = np.radians(np.arange(0.0, 180.0, 1.0))
    c, s = np.abs(np.cos(yaws)), np.abs(np.sin(yaws))
    dy = 2.0 * box.half[1]
    best = int(np.argmin(np.abs(dy - (length * s + width * c))))
    missing = (length * c[best] + width * s[best]) - 2.0 * box.half[0]
    if missing <= 0.0:
        return box
    grow = min(missing, OCCLUSION_M)
    near = box.centre[0] - box.half[0]
    half_x = box.half[0] + 0.5 * grow
    return AABB((near + half_x, box.centre[1], box.centre[2]), (half_x, box.half[1], box.half[2]))


def scan_check(boxes: Sequence[AABB], obj: str, face: str, tm: str, unit: str, pickup: bool,
               gap_m: float) -> tuple[bool, str, dict[str, list[str]]]:  # fmt: skip
    """Match the scan with the ledger: `obj` on `unit` before a pick-up, on the module
    `tm` before a delivery, nothing else on either. Returns (consistent, the reason when
    not, the report's summary)."""
    holder = unit if pickup else tm
    expected = {tm: [], unit: []}
    size = expected_size(obj, face)
    expected[holder] = [Possession(obj, size)]
    on = unit_by_gap(gap_m, tm, unit)
    seen = {}  # what the camera saw, by the box that is matched
    for box in boxes:
        opened = far_side_open(box, size) if on(box) == unit else box
        seen[id(opened)] = (opened, box)
    report = match_possessions([o for o, _ in seen.values()], expected, on)
    summary = report.summary()
    if report.consistent:
        return True, "", summary
    why = []
    for where, p in report.missing:
        why.append(f"{p.object_id} not seen on {where}")
    for m in report.moved:
        why.append(f"{m.possession.object_id} seen on {m.unit}, not on {m.expected_unit}")
    for where, box in report.unexpected:
        size = " x ".join(f"{2000 * v:.0f}" for v in seen[id(box)][1].half[:2])
        why.append(f"an unexpected object ({size} mm) on {where}")
    return False, "the camera disagrees with the ledger: " + "; ".join(why), summary
