"""Scan detections against the units' expected possessions (`match_possessions`)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from transfertwin._errors import InputError
from transfertwin.perception import (
    AABB,
    Possession,
    footprint_over_yaw,
    match_possessions,
    size_distance,
    unit_by_gap,
)

UNIT = unit_by_gap(0.012)
CORE = (0.20, 0.09, 0.08)  # L, W, H at yaw 0
SMALL = (0.12, 0.06, 0.05)


def _box(x: float, y: float, size: tuple[float, float, float], yaw_deg: float = 0.0) -> AABB:
    """The AABB of an object of extents (L, W, H) at yaw, resting on the belt."""
    c, s = abs(math.cos(math.radians(yaw_deg))), abs(math.sin(math.radians(yaw_deg)))
    length, width, height = size
    half = (0.5 * (length * c + width * s), 0.5 * (length * s + width * c), 0.5 * height)
    return AABB((x, y, half[2]), half, 500)


def test_size_distance_is_zero_at_any_yaw_and_sees_a_wrong_height() -> None:
    for yaw in (0, 17, 45, 90, 135):
        assert size_distance(_box(0, 0, CORE, yaw), CORE) < 1e-3
    assert size_distance(_box(0, 0, CORE, 30), CORE, math.radians(30)) < 1e-12
    assert size_distance(_box(0, 0, CORE, 30), CORE, 0.0) > 0.02  # wrong yaw given
    taller = _box(0, 0, (0.20, 0.09, 0.12))
    assert size_distance(taller, CORE) == pytest.approx(0.04)


def test_a_round_objects_real_footprint_is_matched_where_its_turned_box_is_not() -> None:
    # a disc of 200 mm: its footprint is 200 x 200 at every yaw, its yaw-0 box turned by 45
    # degrees would cover 283 x 283
    ring = [(0.1 * math.cos(a), 0.1 * math.sin(a)) for a in np.linspace(0, 2 * math.pi, 721)]
    fp = footprint_over_yaw(np.array(ring), 180)
    assert len(fp) == 180 and all(f == pytest.approx((0.2, 0.2), abs=1e-4) for f in fp)
    disc = (0.2, 0.2, 0.05)
    seen = AABB((0.2, 0.0, 0.025), (0.1, 0.1, 0.025))
    assert size_distance(seen, disc, None, fp) == pytest.approx(0.0, abs=1e-4)
    assert size_distance(seen, disc, math.radians(45), fp) == pytest.approx(0.0, abs=1e-4)
    # a bar's footprint at a known yaw picks that yaw's entry
    bar = footprint_over_yaw(np.array([(-0.1, -0.02), (0.1, 0.02)]), 180)
    assert bar[90] == pytest.approx((0.04, 0.2))
    assert size_distance(AABB((0, 0, 0.025), (0.02, 0.1, 0.025)), (0.2, 0.04, 0.05),
                         math.radians(90), bar) == pytest.approx(0.0, abs=1e-9)  # fmt: skip
    with pytest.raises(InputError, match="footprint_m"):
        Possession("o1", disc, footprint_m=((0.2, -0.1),))
    with pytest.raises(InputError, match="points"):
        footprint_over_yaw(np.zeros((3, 3)))


def test_objects_on_their_units_are_matched() -> None:
    boxes = [_box(-0.33, 0.0, CORE, 40), _box(0.25, 0.09, SMALL, 10)]
    expected = {"TM": [Possession("o1", CORE)], "TU": [Possession("o23", SMALL)]}
    report = match_possessions(boxes, expected, UNIT)
    assert report.consistent
    pairs = {(m.unit, m.possession.object_id) for m in report.matched}
    assert pairs == {("TM", "o1"), ("TU", "o23")}
    assert all(m.size_error_m < 1e-3 and m.position_error_m is None for m in report.matched)


def test_sizes_decide_who_is_who_when_positions_are_unknown() -> None:
    boxes = [_box(-0.5, 0.0, SMALL, 70), _box(-0.2, 0.0, CORE, 5)]
    expected = {"TM": [Possession("big", CORE), Possession("small", SMALL)]}
    report = match_possessions(boxes, expected, UNIT)
    pairs = {m.possession.object_id: m.box.centre[0] for m in report.matched}
    assert pairs == {"big": -0.2, "small": -0.5}


def test_positions_decide_between_two_equal_objects() -> None:
    boxes = [_box(-0.5, 0.0, CORE), _box(-0.2, 0.0, CORE)]
    expected = {"TM": [Possession("a", CORE, (-0.21, 0.0)), Possession("b", CORE, (-0.49, 0.0))]}
    report = match_possessions(boxes, expected, UNIT)
    pairs = {m.possession.object_id: m.box.centre[0] for m in report.matched}
    assert pairs == {"a": -0.2, "b": -0.5}
    assert max(m.position_error_m for m in report.matched) == pytest.approx(0.01)


def test_missing_unexpected_and_moved() -> None:
    boxes = [
        _box(-0.33, 0.0, CORE),  # o1, on the TM as expected
        _box(0.25, 0.0, SMALL),  # o23, expected on the TM but lying on the TU
        _box(-0.55, 0.09, (0.05, 0.05, 0.05)),  # nobody's
    ]
    expected = {
        "TM": [Possession("o1", CORE), Possession("o23", SMALL)],
        "TU": [Possession("o7", (0.3, 0.1, 0.1))],
    }
    report = match_possessions(boxes, expected, UNIT)
    assert [m.possession.object_id for m in report.matched] == ["o1"]
    assert [(m.possession.object_id, m.expected_unit, m.unit) for m in report.moved] == [
        ("o23", "TM", "TU")
    ]
    assert [(u, p.object_id) for u, p in report.missing] == [("TU", "o7")]
    assert [(u, b.centre[0]) for u, b in report.unexpected] == [("TM", -0.55)]
    assert not report.consistent
    assert report.summary()["moved"] == ["o23: TM -> TU"]


def test_a_box_too_far_from_its_known_position_is_not_a_match() -> None:
    report = match_possessions(
        [_box(-0.2, 0.0, CORE)], {"TM": [Possession("o1", CORE, (-0.5, 0.0))]}, UNIT
    )
    assert not report.matched and not report.moved
    assert len(report.missing) == 1 and len(report.unexpected) == 1


def test_nothing_expected_nothing_seen_is_consistent() -> None:
    assert match_possessions([], {"TM": [], "TU": []}, UNIT).consistent


def test_bad_arguments_are_refused() -> None:
    with pytest.raises(InputError):
        Possession("x", (0.1, -0.1, 0.1))
    twice = {"TM": [Possession("o1", CORE)], "TU": [Possession("o1", CORE)]}
    with pytest.raises(InputError, match="more than once"):
        match_possessions([], twice, UNIT)
    with pytest.raises(InputError, match="tolerances"):
        match_possessions([], {}, UNIT, size_tol_m=0.0)
