"""Belt OTS state sets for the return transfer TU -> TM (mirror of Eq. 5.7–5.9)."""

from __future__ import annotations

import numpy as np
import pytest

from transfertwin.ots import (
    ASSET_TM,
    ASSET_TU,
    Conveyor,
    TransferDirection,
    belt_sets,
    make_states,
)

EPS = 1e-9
H = 0.125
BACK = belt_sets(TransferDirection.TU_TO_TM)
FORWARD = belt_sets(TransferDirection.TM_TO_TU)


def state(**kw: float) -> np.ndarray:
    """One belt state (11,); defaults: a nominal return pre-transfer state on the TU."""
    base = {
        "a": ASSET_TU, "x": 0.25, "y": 0.0, "z": 0.05, "s_x": 0.1, "s_y": 0.05,
        "s_z": 0.05, "theta": 0.0, "f": 0, "c": int(Conveyor.BOTH), "t": 0.0,
    }  # fmt: skip
    return make_states(**{**base, **kw})[0]


def on_tm(**kw: float) -> np.ndarray:
    """A nominal success state of the return transfer, overridable."""
    return state(**{"a": ASSET_TM, "x": -0.3, "t": 5.0, **kw})


def test_return_bundle_swaps_the_assets() -> None:
    assert BACK.direction is TransferDirection.TU_TO_TM
    assert (BACK.a_pre, BACK.a_post) == (ASSET_TU, ASSET_TM)


def test_eq_5_7_mirror_pre_requires_tu_possession_and_tu_belts() -> None:
    assert bool(BACK.pre.contains(state()))
    assert not bool(BACK.pre.contains(state(a=ASSET_TM)))
    assert not bool(BACK.pre.contains(state(t=1.0)))


@pytest.mark.parametrize(
    ("kw", "inside"),
    [
        ({"x": H, "s_x": H}, True),  # x - s_x == tu_x_min
        ({"x": H - EPS, "s_x": H}, False),
        ({"x": 0.5 - H, "s_x": H}, True),  # x + s_x == tu_x_max
        ({"x": 0.5 - H + EPS, "s_x": H}, False),
        ({"y": 0.2 - H + EPS, "s_y": H}, False),
    ],
)
def test_eq_5_7_mirror_pre_bounds_are_inclusive(kw: dict, inside: bool) -> None:
    assert bool(BACK.pre.contains(state(**kw))) is inside


def test_eq_5_8_mirror_success_nominal() -> None:
    assert bool(BACK.success.contains(on_tm()))
    assert not bool(BACK.success.contains(on_tm(a=ASSET_TU)))
    assert not bool(BACK.success.contains(on_tm(t=30.0)))


@pytest.mark.parametrize(("x", "inside"), [(-0.2, False), (-0.2 - EPS, True), (-0.1, False)])
def test_eq_5_8_mirror_x_threshold_is_strict(x: float, inside: bool) -> None:
    assert bool(BACK.success.contains(on_tm(x=x, s_x=0.1))) is inside


@pytest.mark.parametrize(
    ("kw", "inside"),
    [
        ({"x": -0.65 + H, "s_x": H}, True),  # x - s_x == tm_x_min
        ({"x": -0.65 + H - EPS, "s_x": H}, False),
        ({"x": -0.25, "s_x": 0.25}, True),  # x + s_x == tm_x_max
        ({"x": -0.25 + EPS, "s_x": 0.25}, False),
        ({"y": -0.2 + H - EPS, "s_y": H}, False),
    ],
)
def test_eq_5_8_mirror_success_requires_full_overlap_with_tm_belts(kw: dict, inside: bool) -> None:
    assert bool(BACK.success.contains(on_tm(**kw))) is inside


def test_eq_5_9_failure_set_is_the_same_in_both_directions() -> None:
    assert BACK.failure == FORWARD.failure


def test_eq_5_8_mirrored_states_swap_membership() -> None:
    forward_success = state(x=0.3, t=5.0)
    mirrored = state(a=ASSET_TM, x=-0.3, t=5.0)
    assert bool(FORWARD.success.contains(forward_success))
    assert bool(BACK.success.contains(mirrored))
    assert not bool(BACK.success.contains(forward_success))
    assert not bool(FORWARD.success.contains(mirrored))


def test_nan_state_is_in_no_return_pre_or_success_set() -> None:
    s = on_tm(x=np.nan)
    assert not bool(BACK.success.contains(s))
    assert not bool(BACK.pre.contains(state(y=np.nan)))
    assert bool(BACK.failure.contains(s))
