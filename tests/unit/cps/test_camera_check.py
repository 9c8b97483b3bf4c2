"""The module's camera against the ledger before an OTS is formed (docs/architecture.md,
"Operation"): missing, moved and unexpected objects stop the step with the reason."""

from __future__ import annotations

from transfertwin.cps.apps._camera import expected_size, scan_check
from transfertwin.perception import AABB

GAP = 0.02


def _box(obj: str, face: str, x: float, y: float = 0.0, swap: bool = False) -> AABB:
    size = expected_size(obj, face)
    half = (size[1] / 2, size[0] / 2, size[2] / 2) if swap else tuple(v / 2 for v in size)
    return AABB((x, y, half[2]), half)


def test_the_object_where_the_ledger_says_is_consistent_at_any_yaw():
    ok, why, summary = scan_check([_box("o1", "front", -0.3, swap=True)], "o1", "front",
                                  "TM_1", "TU_B", pickup=False, gap_m=GAP)  # fmt: skip
    assert ok and why == "" and summary["matched"] == ["o1"]
    ok, _, _ = scan_check([_box("o1", "back", 0.3)], "o1", "back", "TM_1", "TU_A",
                          pickup=True, gap_m=GAP)  # fmt: skip
    assert ok


def test_missing_moved_and_unexpected_objects_are_named():
    ok, why, _ = scan_check([], "o1", "front", "TM_1", "TU_A", pickup=True, gap_m=GAP)
    assert not ok and why.endswith("o1 not seen on TU_A")
    ok, why, _ = scan_check([_box("o1", "front", -0.3)], "o1", "front", "TM_1", "TU_A",
                            pickup=True, gap_m=GAP)  # fmt: skip
    assert not ok and "o1 seen on TM_1, not on TU_A" in why
    tiny = AABB((0.3, 0.0, 0.01), (0.02, 0.02, 0.01))
    ok, why, summary = scan_check([_box("o1", "front", -0.3), tiny], "o1", "front", "TM_1",
                                  "TU_B", pickup=False, gap_m=GAP)  # fmt: skip
    assert not ok and "an unexpected object (40 x 40 mm) on TU_B" in why
    assert summary["matched"] == ["o1"]
