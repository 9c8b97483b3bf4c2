"""Belt state vector (Eq. 5.4–5.6): columns, codes, builder, conveyor code."""

from __future__ import annotations

import numpy as np
import pytest

from transfertwin import InputError
from transfertwin.ots import (
    ASSET_TM,
    ASSET_TU,
    N_COLS,
    Col,
    Conveyor,
    Face,
    conveyor_of,
    make_states,
)


def test_eq_5_4_column_order() -> None:
    names = [c.name for c in Col]
    assert names == ["A", "X", "Y", "Z", "SX", "SY", "SZ", "THETA", "F", "C", "T"]
    assert [int(c) for c in Col] == list(range(11))
    assert N_COLS == 11


def test_eq_5_4_asset_codes() -> None:
    assert (ASSET_TM, ASSET_TU) == (0, 1)


def test_eq_5_5_face_codes_and_labels() -> None:
    assert (int(Face.FRONT), int(Face.BACK)) == (0, 1)
    assert [f.label for f in Face] == ["front", "back"]


def test_eq_5_6_conveyor_codes_and_labels() -> None:
    assert (int(Conveyor.LEFT), int(Conveyor.RIGHT), int(Conveyor.BOTH)) == (0, 1, 2)
    assert Conveyor.BOTH.label == "both"


def test_make_states_places_named_columns() -> None:
    s = make_states(
        a=ASSET_TU, x=0.1, y=-0.05, z=0.02, s_x=0.12, s_y=0.04, s_z=0.03,
        theta=0.5, f=Face.BACK, c=Conveyor.RIGHT, t=1.5,
    )  # fmt: skip
    assert s.shape == (1, 11)
    expected = [1, 0.1, -0.05, 0.02, 0.12, 0.04, 0.03, 0.5, 1, 1, 1.5]
    np.testing.assert_allclose(s[0], expected)


def test_make_states_broadcasts_to_a_batch() -> None:
    s = make_states(x=np.array([-0.3, -0.2, -0.1]), y=0.0, s_x=0.1, s_y=0.05)
    assert s.shape == (3, 11)
    np.testing.assert_array_equal(s[:, Col.X], [-0.3, -0.2, -0.1])
    np.testing.assert_array_equal(s[:, Col.A], ASSET_TM)
    np.testing.assert_array_equal(s[:, Col.T], 0.0)


def test_make_states_derives_conveyor_when_not_given() -> None:
    s = make_states(x=-0.3, y=np.array([0.094, 0.0, -0.094]), s_x=0.1, s_y=0.05)
    np.testing.assert_array_equal(s[:, Col.C], [Conveyor.LEFT, Conveyor.BOTH, Conveyor.RIGHT])


def test_make_states_allows_nan_theta() -> None:
    s = make_states(x=0.0, y=0.0, s_x=0.1, s_y=0.05, theta=np.nan)
    assert np.isnan(s[0, Col.THETA])


@pytest.mark.parametrize(
    "kwargs",
    [{"a": 2}, {"f": 3}, {"c": 5}, {"s_x": -0.1}, {"s_z": -1e-3}, {"x": np.zeros((2, 2))},
     {"x": np.zeros(2), "y": np.zeros(3)}],
)  # fmt: skip
def test_make_states_rejects_bad_columns(kwargs: dict) -> None:
    base = {"x": 0.0, "y": 0.0, "s_x": 0.1, "s_y": 0.05, "c": Conveyor.BOTH}
    with pytest.raises(InputError, match=r"Eq\. 5\.4"):
        make_states(**{**base, **kwargs})


def test_eq_5_6_conveyor_of_overlap_rules() -> None:
    y = np.array([0.094, -0.094, 0.0, 0.05, 0.05])
    s_y = np.array([0.05, 0.05, 0.05, 0.05, 0.06])
    np.testing.assert_array_equal(
        conveyor_of(y, s_y),
        [Conveyor.LEFT, Conveyor.RIGHT, Conveyor.BOTH, Conveyor.LEFT, Conveyor.BOTH],
    )


def test_eq_5_6_touching_a_belt_edge_is_no_overlap() -> None:
    gap = 0.0625  # belt edges at y = +-0.0625 (exact binary fractions)
    assert conveyor_of(0.0625, 0.125, belt_gap_half_width=gap) == Conveyor.LEFT
    assert conveyor_of(-0.0625, 0.125, belt_gap_half_width=gap) == Conveyor.RIGHT
    assert conveyor_of(0.0625, 0.1251, belt_gap_half_width=gap) == Conveyor.BOTH


def test_eq_5_6_box_within_the_belt_gap_drives_both_belts() -> None:
    assert conveyor_of(0.0, 0.0625, belt_gap_half_width=0.0625) == Conveyor.BOTH


def test_eq_5_6_conveyor_of_scalar_gives_0d() -> None:
    assert conveyor_of(0.1, 0.02).shape == ()


@pytest.mark.parametrize(("y", "s_y", "gap"), [(np.nan, 0.1, 0.005), (0.0, -0.1, 0.005),
                                               (0.0, 0.1, -0.001)])  # fmt: skip
def test_eq_5_6_conveyor_of_rejects_bad_input(y: float, s_y: float, gap: float) -> None:
    with pytest.raises(InputError, match=r"Eq\. 5\.6"):
        conveyor_of(y, s_y, belt_gap_half_width=gap)
