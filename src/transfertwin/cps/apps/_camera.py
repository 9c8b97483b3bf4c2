"""The transport module's depth camera in the loop (issue 28, item 3; docs/architecture.md,
"Operation"): before an OTS is formed, what the camera sees of the module's belts and the
docked unit's is matched with what the ledger says each holds (`match_possessions`,
Sec. 5.5); an object missing, seen on the other unit, or a box nobody expects stops the
step with the reason, which goes into the order's history.

What the ledger says an object is comes from its model: the extents of its convex hulls
lying on the face it was loaded on (yaw 0), compared over every yaw (the camera's AABB
cannot tell the yaw).
"""

from __future__ import annotations

from collections.abc import Sequence
from functools import lru_cache

import numpy as np

from transfertwin.perception import AABB, Possession, match_possessions, unit_by_gap

__all__ = ["expected_size", "scan_check"]


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


def scan_check(boxes: Sequence[AABB], obj: str, face: str, tm: str, unit: str, pickup: bool,
               gap_m: float) -> tuple[bool, str, dict[str, list[str]]]:  # fmt: skip
    """Match the scan with the ledger: `obj` on `unit` before a pick-up, on the module
    `tm` before a delivery, nothing else on either. Returns (consistent, the reason when
    not, the report's summary)."""
    holder = unit if pickup else tm
    expected = {tm: [], unit: []}
    expected[holder] = [Possession(obj, expected_size(obj, face))]
    report = match_possessions(boxes, expected, unit_by_gap(gap_m, tm, unit))
    summary = report.summary()
    if report.consistent:
        return True, "", summary
    why = []
    for where, p in report.missing:
        why.append(f"{p.object_id} not seen on {where}")
    for m in report.moved:
        why.append(f"{m.possession.object_id} seen on {m.unit}, not on {m.expected_unit}")
    for where, box in report.unexpected:
        size = " x ".join(f"{2000 * v:.0f}" for v in box.half[:2])
        why.append(f"an unexpected object ({size} mm) on {where}")
    return False, "the camera disagrees with the ledger: " + "; ".join(why), summary
