"""The module's camera against the ledger before an OTS is formed (docs/architecture.md,
"Operation"): missing, moved and unexpected objects stop the step with the reason."""

from __future__ import annotations

import pytest

from transfertwin.cps.apps._camera import (
    SIZE_TOL_M,
    expected_footprint,
    expected_size,
    far_side_open,
    height_key,
    scan_check,
)
from transfertwin.perception import AABB, size_distance

GAP = 0.02


def _box(obj: str, face: str, x: float, y: float = 0.0, swap: bool = False) -> AABB:
    size = expected_size(obj, face)
    half = (size[1] / 2, size[0] / 2, size[2] / 2) if swap else tuple(v / 2 for v in size)
    return AABB((x, y, half[2]), half)


def test_the_object_where_the_ledger_says_is_consistent_at_any_yaw():
    ok, why, summary, _ = scan_check([_box("o1", "front", -0.3, swap=True)], "o1", "front",
                                  "TM_1", "TU_B", pickup=False, gap_m=GAP)  # fmt: skip
    assert ok and why == "" and summary["matched"] == ["o1"]
    ok, _, _, _ = scan_check([_box("o1", "back", 0.3)], "o1", "back", "TM_1", "TU_A",
                          pickup=True, gap_m=GAP)  # fmt: skip
    assert ok


def test_missing_moved_and_unexpected_objects_are_named():
    ok, why, _, _ = scan_check([], "o1", "front", "TM_1", "TU_A", pickup=True, gap_m=GAP)
    assert not ok and why.endswith("o1 not seen on TU_A")
    ok, why, _, _ = scan_check([_box("o1", "front", -0.3)], "o1", "front", "TM_1", "TU_A",
                            pickup=True, gap_m=GAP)  # fmt: skip
    assert not ok and "o1 seen on TM_1, not on TU_A" in why
    tiny = AABB((0.3, 0.0, 0.01), (0.02, 0.02, 0.01))
    ok, why, summary, _ = scan_check([_box("o1", "front", -0.3), tiny], "o1", "front", "TM_1",
                                  "TU_B", pickup=False, gap_m=GAP)  # fmt: skip
    assert not ok and "an unexpected object (40 x 40 mm) on TU_B" in why
    assert summary["matched"] == ["o1"]


def test_a_far_end_hidden_on_the_unit_is_matched_on_width_and_height():
    full = _box("o9", "front", 0.26)
    length = 2 * full.half[0]
    for cut, ok_expected in ((0.046, True), (0.12, False)):
        near = full.centre[0] - full.half[0]
        half_x = 0.5 * (length - cut)
        seen = AABB((near + half_x, 0.0, full.centre[2]), (half_x, *full.half[1:]))
        ok, why, _, _ = scan_check([seen], "o9", "front", "TM_1", "TU_A", pickup=True, gap_m=GAP)
        assert ok is ok_expected, (cut, why)
    # extended away from the camera only, and never beyond the expected length
    grown = far_side_open(AABB((0.2, 0.0, 0.05), (0.08, *full.half[1:])), expected_footprint("o9",
                                                                                        "front"))
    assert grown.centre[0] - grown.half[0] == pytest.approx(0.12)
    assert 2 * grown.half[0] <= length + 1e-9
    # on the module's own belts (a delivery) a short box stays short: the camera sees it whole
    short = AABB((-0.3, 0.0, full.centre[2]), (full.half[0] - 0.023, *full.half[1:]))
    ok, _, _, _ = scan_check([short], "o9", "front", "TM_1", "TU_A", pickup=False, gap_m=GAP)
    assert not ok


def test_the_modules_camera_sees_a_core_in_the_middle_of_the_unit_as_the_ledger_says():
    """A real scan (MuJoCo depth frames, the perception pipeline): o9 where a pick-up puts it
    is seen short at its far end and still matched."""
    from transfertwin.cps.apps._environment import system_for
    from transfertwin.cps.hal import load_scene
    from transfertwin.perception import CameraIntrinsics, DepthCamera, Workspace, workspace_scan
    from transfertwin.sim import DockingError

    scene = load_scene()
    system = system_for("o9", "m", scene)
    system.reset(DockingError())
    tx, ty, _ = system.tu_pose
    system.place("front", 0.0, tx + 0.25, ty)
    system.clock.wait(scene.placement.settle_time_s)
    workspace = Workspace.for_layout(scene.layout, scene.gap_m, docked=True)
    with DepthCamera(system.model, system.data, intrinsics=CameraIntrinsics(160, 120)) as cam:
        detection, _ = workspace_scan(cam, workspace, seed=1)
    (box,) = detection.boxes
    assert 2 * box.half[0] < expected_size("o9", "front")[0] - 0.03  # its far end is hidden
    ok, why, _, _ = scan_check(detection.boxes, "o9", "front", "TM_1", "TU_A", pickup=True,
                            gap_m=scene.gap_m)  # fmt: skip
    assert ok, why


def test_a_height_the_model_gets_wrong_is_learnt_once_and_then_expected():
    size = expected_size("o10", "front")
    taller = AABB((0.3, 0.0, 0.0), (size[0] / 2, size[1] / 2, size[2] / 2 + 0.016))
    verdict = scan_check([taller], "o10", "front", "TM_1", "TU_A", pickup=True, gap_m=GAP)
    assert verdict.ok and verdict.height_m == pytest.approx(size[2] + 0.032)
    assert verdict.summary["matched"] == ["o10"] and "stands" in verdict.summary["learnt"][0]
    heights = {height_key("o10", "front"): verdict.height_m}
    # learnt: the same box matches outright, and nothing more is learnt
    again = scan_check([taller], "o10", "front", "TM_1", "TU_A", pickup=True, gap_m=GAP,
                       heights=heights)  # fmt: skip
    assert again.ok and again.height_m is None and "learnt" not in again.summary
    # once learnt, a box of the model's height disagrees like any other
    model = _box("o10", "front", 0.3)
    refused = scan_check([model], "o10", "front", "TM_1", "TU_A", pickup=True, gap_m=GAP,
                         heights=heights)  # fmt: skip
    assert not refused.ok and "o10 not seen on TU_A" in refused.why
    # the other face is not learnt by it
    assert scan_check([_box("o10", "back", 0.3)], "o10", "back", "TM_1", "TU_A", pickup=True,
                      gap_m=GAP, heights=heights).ok  # fmt: skip


def test_no_height_is_learnt_from_a_scan_that_disagrees_otherwise():
    size = expected_size("o10", "front")
    far_too_tall = AABB((0.3, 0.0, 0.0), (size[0] / 2, size[1] / 2, size[2] / 2 + 0.03))
    assert not scan_check([far_too_tall], "o10", "front", "TM_1", "TU_A", pickup=True,
                          gap_m=GAP).ok  # fmt: skip
    taller = AABB((0.3, 0.0, 0.0), (size[0] / 2, size[1] / 2, size[2] / 2 + 0.016))
    # wider than the core is at any yaw (its diagonal is 251 mm), on the module's belts
    wider = AABB((-0.3, 0.0, 0.0), (size[0] / 2, size[1] / 2 + 0.1, size[2] / 2 + 0.016))
    assert not scan_check([wider], "o10", "front", "TM_1", "TU_A", pickup=False, gap_m=GAP).ok
    tiny = AABB((-0.3, 0.0, 0.01), (0.02, 0.02, 0.01))  # something on the module as well
    verdict = scan_check([taller, tiny], "o10", "front", "TM_1", "TU_A", pickup=True, gap_m=GAP)
    assert not verdict.ok and verdict.height_m is None and "unexpected" in verdict.why
    # on the module before a delivery the same rule holds for the module's belts
    on_module = AABB((-0.3, 0.0, 0.0), taller.half)
    assert scan_check([on_module], "o10", "front", "TM_1", "TU_A", pickup=False, gap_m=GAP).ok


def test_a_yawed_core_is_matched_on_its_real_footprint():
    size, fp = expected_size("o3", "front"), expected_footprint("o3", "front")
    fx, fy = fp[45]  # the rounded core at 45 degrees covers less than its box turned
    seen = AABB((-0.3, 0.0, size[2] / 2), (fx / 2, fy / 2, size[2] / 2))
    assert size_distance(seen, size) > SIZE_TOL_M  # its yaw-0 box fits at no yaw
    verdict = scan_check([seen], "o3", "front", "TM_1", "TU_A", pickup=False, gap_m=GAP)
    assert verdict.ok and verdict.height_m is None, verdict.why
