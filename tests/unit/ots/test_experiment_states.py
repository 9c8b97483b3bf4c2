"""Discrete pre-transfer states of the study (Eq. 6.1–6.10, 6.20–6.24).

Expected counts come from the text: 924 states per object (Eq. 6.20, Table 6.5)
and 360 states per series (Sec. 6.6); |Θ_single| = 25 + 51 + 26 by counting the
integer ranges of Eq. 6.5 by hand.
"""

from __future__ import annotations

import csv
import io
import math
from collections import Counter

import numpy as np
import pytest

from transfertwin import InputError
from transfertwin.ots import (
    EXPERIMENT_PRE_X_MIN,
    P_LEFT,
    P_MIDDLE,
    P_RIGHT,
    SERIES_ORDER,
    STATES_CSV_HEADER,
    THETA_ALL,
    THETA_BOTH,
    THETA_SINGLE,
    Col,
    Conveyor,
    Face,
    PreTransferState,
    check_theta_deg,
    conveyor_of,
    experiment_pre_transfer_set,
    experiment_states,
    filter_theta_step,
    parse_conveyor,
    parse_face,
    pre_transfer_set,
    series,
    state_index,
    states_csv,
)


def test_eq_6_3_positions() -> None:
    assert P_LEFT == (-0.325, 0.094)
    assert P_MIDDLE == (-0.325, 0.0)
    assert P_RIGHT == (-0.325, -0.094)


def test_eq_6_4_theta_is_every_integer_from_minus_179_to_180() -> None:
    assert len(THETA_ALL) == 360
    assert THETA_ALL[0] == -179 and THETA_ALL[-1] == 180


def test_eq_6_5_theta_single_ranges() -> None:
    assert len(THETA_SINGLE) == 25 + 51 + 26
    for inside in (-179, -155, -25, 0, 25, 155, 180):
        assert inside in THETA_SINGLE
    for outside in (-154, -26, 26, 154):
        assert outside not in THETA_SINGLE


def test_eq_6_6_theta_both_is_the_complement() -> None:
    assert len(THETA_BOTH) == 360 - 102
    assert not set(THETA_BOTH) & set(THETA_SINGLE)
    assert set(THETA_BOTH) | set(THETA_SINGLE) == set(THETA_ALL)


def test_eq_6_7_there_are_924_unique_states() -> None:
    states = experiment_states()
    assert len(states) == 924
    assert len({s.key for s in states}) == 924


def test_eq_6_8_6_10_counts_and_positions_per_face_and_conveyor() -> None:
    counts = Counter((s.face, s.conveyor) for s in experiment_states())
    for face in ("front", "back"):
        assert counts[(face, "left")] == 102
        assert counts[(face, "both")] == 258
        assert counts[(face, "right")] == 102
    expected_xy = {"left": P_LEFT, "both": P_MIDDLE, "right": P_RIGHT}
    for s in experiment_states():
        assert (s.x_m, s.y_m) == expected_xy[s.conveyor]


def test_eq_6_7_stable_order() -> None:
    states = experiment_states()
    assert states[0].key == ("front", "left", -179)
    assert states[101].key == ("front", "left", 180)
    assert states[102].key == ("front", "both", -154)
    assert states[360].key == ("front", "right", -179)
    assert states[462].key == ("back", "left", -179)
    assert states[-1].key == ("back", "right", 180)
    assert experiment_states() == states


def test_state_index_matches_the_order() -> None:
    for i in (0, 101, 102, 500, 923):
        assert state_index(*experiment_states()[i].key) == i
    with pytest.raises(InputError, match=r"Eq\. 6\.7"):
        state_index("front", "left", 90)


@pytest.mark.parametrize(("face", "side"), SERIES_ORDER)
def test_eq_6_21_6_24_each_series_has_360_states_one_per_theta(face: str, side: str) -> None:
    s = series(face, side)
    assert len(s) == 360
    assert [x.theta_deg for x in s] == list(THETA_ALL)
    assert {x.face for x in s} == {face}
    assert {x.conveyor for x in s} == {"both", side}


def test_eq_6_21_6_24_series_cover_all_states() -> None:
    covered = {x.key for fs in SERIES_ORDER for x in series(*fs)}
    assert covered == {s.key for s in experiment_states()}


def test_series_order() -> None:
    expected = (("front", "left"), ("front", "right"), ("back", "left"), ("back", "right"))
    assert expected == SERIES_ORDER


def test_series_rejects_both_as_side() -> None:
    with pytest.raises(InputError, match="side"):
        series("front", "both")


def test_states_csv_round_trips() -> None:
    text = states_csv()
    assert text.splitlines()[0] == STATES_CSV_HEADER == "face,conveyor,theta_deg,x_m,y_m"
    rows = list(csv.DictReader(io.StringIO(text)))
    assert len(rows) == 924
    assert rows[0] == {"face": "front", "conveyor": "left", "theta_deg": "-179",
                       "x_m": "-0.325", "y_m": "0.094"}  # fmt: skip
    for row, s in zip(rows, experiment_states(), strict=True):
        assert (row["face"], row["conveyor"], int(row["theta_deg"])) == s.key
        assert (float(row["x_m"]), float(row["y_m"])) == (s.x_m, s.y_m)
    assert text.endswith("\n")


def test_states_csv_of_a_subset() -> None:
    assert states_csv(series("back", "right")[:2]).count("\n") == 3


def test_filter_theta_step_30_keeps_28_states() -> None:
    # multiples of 30 in -179..180: 12 angles; in Θ_single: 0 and 180 -> 2 + 10 + 2 per face
    kept = filter_theta_step(experiment_states(), 30)
    assert len(kept) == 28
    assert all(s.theta_deg % 30 == 0 for s in kept)


def test_filter_theta_step_edge_cases() -> None:
    assert len(filter_theta_step(experiment_states(), 1)) == 924
    assert len(filter_theta_step(experiment_states(), 360)) == 4  # θ = 0 at left and right
    for bad in (0, -5, 361, 2.5, True):
        with pytest.raises(InputError, match="step"):
            filter_theta_step(experiment_states(), bad)  # type: ignore[arg-type]


def test_parse_face_and_conveyor() -> None:
    assert parse_face(" Front ") == "front"
    assert parse_conveyor("BOTH") == "both"
    for bad_face in ("side", "", None, 0):
        with pytest.raises(InputError, match="face") as info:
            parse_face(bad_face)
        assert "\n" not in str(info.value)
    with pytest.raises(InputError, match="conveyor"):
        parse_conveyor("middle")


@pytest.mark.parametrize(
    ("value", "expected"),
    [(180, 180), (-179, -179), ("15", 15), (" -15 ", -15), (15.0, 15), (np.int64(3), 3)],
)
def test_check_theta_deg_accepts_integers(value: object, expected: int) -> None:
    assert check_theta_deg(value) == expected


@pytest.mark.parametrize("value", [-180, 181, 1.5, True, "abc", "1.5", None, math.nan])
def test_eq_6_4_check_theta_deg_rejects(value: object) -> None:
    with pytest.raises(InputError, match=r"Eq\. 6\.4"):
        check_theta_deg(value)


def test_pre_transfer_state_normalises_and_validates() -> None:
    s = PreTransferState("FRONT", "Left", 15, -0.325, 0.094)
    assert s.key == ("front", "left", 15)
    assert s.face_code is Face.FRONT and s.conveyor_code is Conveyor.LEFT
    assert s.theta_rad == pytest.approx(math.radians(15))
    with pytest.raises(InputError):
        PreTransferState("front", "left", 200, -0.325, 0.094)
    with pytest.raises(InputError):
        PreTransferState("front", "left", 15, math.nan, 0.094)


def test_pre_transfer_states_are_frozen_and_hashable() -> None:
    s = experiment_states()[0]
    assert hash(s) == hash(PreTransferState(*s.key, s.x_m, s.y_m))
    with pytest.raises(AttributeError):
        s.theta_deg = 3  # type: ignore[misc]


def test_eq_6_1_to_state_lies_in_the_experiment_pre_transfer_set() -> None:
    s = PreTransferState("back", "left", 10, *P_LEFT)
    vec = s.to_state(s_x=0.12, s_y=0.05, z=0.04, s_z=0.04)
    assert vec.shape == (11,)
    assert vec[Col.F] == Face.BACK and vec[Col.C] == Conveyor.LEFT and vec[Col.T] == 0.0
    assert vec[Col.THETA] == pytest.approx(math.radians(10))
    assert bool(experiment_pre_transfer_set().contains(vec))
    assert conveyor_of(vec[Col.Y], vec[Col.SY]) == Conveyor.LEFT


def test_eq_6_1_far_end_is_stricter_than_eq_5_7() -> None:
    assert EXPERIMENT_PRE_X_MIN == -0.625
    vec = PreTransferState("front", "both", 90, *P_MIDDLE).to_state(s_x=0.315, s_y=0.05)
    assert vec[Col.X] - vec[Col.SX] == pytest.approx(-0.64)
    assert bool(pre_transfer_set().contains(vec))
    assert not bool(experiment_pre_transfer_set().contains(vec))


def test_eq_6_1_experiment_pre_set_rejects_bad_x_min() -> None:
    with pytest.raises(InputError, match=r"Eq\. 6\.1"):
        experiment_pre_transfer_set(x_min=0.1)
