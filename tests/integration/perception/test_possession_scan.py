"""A real two-viewpoint scan matched with what the units say they possess."""

from __future__ import annotations

import math

from transfertwin.ots import POSITIONS
from transfertwin.perception import (
    CameraIntrinsics,
    DepthCamera,
    Possession,
    Workspace,
    ground_truth_aabb,
    match_possessions,
    unit_by_gap,
    workspace_scan,
)
from transfertwin.sim import DockingError, SceneConfig
from transfertwin.study.experiment import system_for

SCENE = SceneConfig()


def _size_at_yaw_0(object_id: str) -> tuple[float, float, float]:
    """What a representation would store: the object's AABB extents at θ = 0, face front."""
    system = system_for(object_id, "m", SCENE)
    system.reset(DockingError())
    system.place("front", 0.0, *POSITIONS["both"])
    system.clock.wait(0.3)
    return tuple(2.0 * h for h in ground_truth_aabb(system).half)


def test_scan_of_a_turned_core_matches_its_known_size() -> None:
    o1_size = _size_at_yaw_0("o1")
    size = _size_at_yaw_0("o23")
    system = system_for("o23", "m", SCENE)
    system.reset(DockingError.from_mm_deg(-4, 2, 0.5))
    system.place("front", math.radians(35), *POSITIONS["both"])
    system.clock.wait(0.3)
    ws = Workspace.for_layout(SCENE.layout, SCENE.gap_m)
    with DepthCamera(system.model, system.data, intrinsics=CameraIntrinsics(160, 120)) as cam:
        boxes = workspace_scan(cam, ws, seed=4)[0].boxes
    unit = unit_by_gap(SCENE.gap_m)
    o23 = Possession("o23", size)

    held = match_possessions(boxes, {"TM": [o23], "TU": []}, unit)
    assert held.consistent and [m.possession.object_id for m in held.matched] == ["o23"]
    assert held.matched[0].size_error_m < 0.02

    believed_on_tu = match_possessions(boxes, {"TM": [], "TU": [o23]}, unit)
    assert [(m.expected_unit, m.unit) for m in believed_on_tu.moved] == [("TU", "TM")]

    plus_o1 = match_possessions(boxes, {"TM": [o23, Possession("o1", o1_size)]}, unit)
    assert [p.object_id for _, p in plus_o1.missing] == ["o1"]

    somewhere_else = match_possessions(boxes, {"TM": [Possession("o23", size, (-0.55, 0.0))]},
                                       unit)  # fmt: skip
    assert not somewhere_else.matched and len(somewhere_else.unexpected) == 1
