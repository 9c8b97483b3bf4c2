"""Belt OTS state sets, forward transfer TM -> TU (Eq. 5.7–5.10), at their bounds."""

from __future__ import annotations

import pickle

import numpy as np
import pytest

from transfertwin import InputError
from transfertwin.ots import (
    ASSET_TM,
    ASSET_TU,
    BeltThresholds,
    Col,
    Conveyor,
    TransferDirection,
    belt_sets,
    failure_set,
    make_states,
    non_terminal_set,
    pre_transfer_set,
    success_set,
)

EPS = 1e-9
H = 0.125  # a half extent that is an exact binary fraction, m
PRE, SUCCESS, FAILURE = pre_transfer_set(), success_set(), failure_set()


def state(**kw: float) -> np.ndarray:
    """One belt state (11,); defaults: a nominal pre-transfer state on the TM."""
    base = {
        "a": ASSET_TM, "x": -0.325, "y": 0.0, "z": 0.05, "s_x": 0.1, "s_y": 0.05,
        "s_z": 0.05, "theta": 0.0, "f": 0, "c": int(Conveyor.BOTH), "t": 0.0,
    }  # fmt: skip
    return make_states(**{**base, **kw})[0]


def on_tu(**kw: float) -> np.ndarray:
    """A nominal success state of the forward transfer, overridable."""
    return state(**{"a": ASSET_TU, "x": 0.3, "t": 5.0, **kw})


def _in(s: object, x: np.ndarray) -> bool:
    return bool(s.contains(x))  # type: ignore[attr-defined]


# --- Eq. 5.7: pre-transfer set ---------------------------------------------------------


def test_eq_5_7_nominal_state_is_pre_transfer() -> None:
    assert _in(PRE, state())


def test_eq_5_7_requires_possession_by_tm() -> None:
    assert not _in(PRE, state(a=ASSET_TU))


@pytest.mark.parametrize(("t", "inside"), [(0.0, True), (1e-12, True), (1e-6, False),
                                           (-1e-6, False), (5.0, False)])  # fmt: skip
def test_eq_5_7_requires_t_equal_t0(t: float, inside: bool) -> None:
    assert _in(PRE, state(t=t)) is inside


@pytest.mark.parametrize(
    ("kw", "inside"),
    [
        ({"x": -0.65 + H, "s_x": H}, True),  # x - s_x == tm_x_min
        ({"x": -0.65 + H - EPS, "s_x": H}, False),
        ({"x": -H, "s_x": H}, True),  # x + s_x == tm_x_max
        ({"x": -H + EPS, "s_x": H}, False),
        ({"y": -0.2 + H, "s_y": H}, True),  # y - s_y == y_min
        ({"y": -0.2 + H - EPS, "s_y": H}, False),
        ({"y": 0.2 - H, "s_y": H}, True),  # y + s_y == y_max
        ({"y": 0.2 - H + EPS, "s_y": H}, False),
    ],
)
def test_eq_5_7_box_bounds_are_inclusive(kw: dict, inside: bool) -> None:
    assert _in(PRE, state(**kw)) is inside


@pytest.mark.parametrize("col", [Col.A, Col.X, Col.Y, Col.SX, Col.SY, Col.T])
def test_eq_5_7_nan_in_a_read_column_is_not_pre_transfer(col: Col) -> None:
    s = state()
    s[col] = np.nan
    assert not _in(PRE, s)


@pytest.mark.parametrize("col", [Col.Z, Col.SZ, Col.THETA, Col.F, Col.C])
def test_eq_5_7_unread_columns_do_not_matter(col: Col) -> None:
    s = state()
    s[col] = np.nan
    assert _in(PRE, s)


# --- Eq. 5.8: success set --------------------------------------------------------------


def test_eq_5_8_nominal_state_is_success() -> None:
    assert _in(SUCCESS, on_tu())


def test_eq_5_8_requires_possession_by_tu() -> None:
    assert not _in(SUCCESS, on_tu(a=ASSET_TM))


@pytest.mark.parametrize(("t", "inside"), [(29.999, True), (30.0, False), (31.0, False)])
def test_eq_5_8_requires_t_below_t_max(t: float, inside: bool) -> None:
    assert _in(SUCCESS, on_tu(t=t)) is inside


@pytest.mark.parametrize(("x", "inside"), [(0.2, False), (0.2 + EPS, True), (0.1, False)])
def test_eq_5_8_x_threshold_is_strict(x: float, inside: bool) -> None:
    assert _in(SUCCESS, on_tu(x=x, s_x=0.1)) is inside


@pytest.mark.parametrize(
    ("kw", "inside"),
    [
        ({"x": 0.25, "s_x": 0.25}, True),  # x - s_x == 0 and x + s_x == 0.5
        ({"x": 0.25 - EPS, "s_x": 0.25}, False),
        ({"x": 0.25 + EPS, "s_x": 0.25}, False),
        ({"y": -0.2 + H, "s_y": H}, True),
        ({"y": -0.2 + H - EPS, "s_y": H}, False),
        ({"y": 0.2 - H, "s_y": H}, True),
        ({"y": 0.2 - H + EPS, "s_y": H}, False),
    ],
)
def test_eq_5_8_success_requires_full_overlap_with_tu_belts(kw: dict, inside: bool) -> None:
    assert _in(SUCCESS, on_tu(**kw)) is inside


@pytest.mark.parametrize("col", [Col.A, Col.X, Col.Y, Col.SX, Col.SY, Col.T])
def test_eq_5_8_nan_in_a_read_column_is_not_success(col: Col) -> None:
    s = on_tu()
    s[col] = np.nan
    assert not _in(SUCCESS, s)


def test_eq_5_8_nan_theta_is_allowed_during_transfer() -> None:
    assert _in(SUCCESS, on_tu(theta=np.nan))


# --- Eq. 5.9: failure set (intent, see the module docstring) ---------------------------


def test_eq_5_9_states_on_the_belts_are_not_failures() -> None:
    on_gap = state(a=ASSET_TU, x=0.0, t=2.0)
    assert not FAILURE.contains(np.stack([state(), on_tu(), on_gap])).any()


@pytest.mark.parametrize(("t", "failed"), [(30.0, False), (30.0 + EPS, True)])
def test_eq_5_9_timeout_is_strict(t: float, failed: bool) -> None:
    assert _in(FAILURE, on_tu(t=t)) is failed


@pytest.mark.parametrize(
    ("kw", "failed"),
    [
        ({"x": -0.65 + H, "s_x": H}, False),  # touching the TM's far end
        ({"x": -0.65 + H - EPS, "s_x": H}, True),
        ({"a": ASSET_TU, "x": 0.5 - H, "s_x": H}, False),  # touching the TU's far end
        ({"a": ASSET_TU, "x": 0.5 - H + EPS, "s_x": H}, True),
        ({"y": -0.2 + H, "s_y": H}, False),
        ({"y": -0.2 + H - EPS, "s_y": H}, True),
        ({"y": 0.2 - H, "s_y": H}, False),
        ({"y": 0.2 - H + EPS, "s_y": H}, True),
    ],
)
def test_eq_5_9_overhang_on_any_single_side_is_failure(kw: dict, failed: bool) -> None:
    # The printed Eq. 5.9 joins both ends of an axis with "and"; one side suffices here.
    assert _in(FAILURE, state(**kw)) is failed


@pytest.mark.parametrize(("z", "failed"), [(0.0, False), (-EPS, True), (-0.5, True)])
def test_eq_5_9_fall_extension_at_z_fall(z: float, failed: bool) -> None:
    assert _in(FAILURE, state(z=z, s_z=0.03)) is failed  # bottom z - 0.03 vs z_fall -0.03


def test_eq_5_9_fall_extension_can_be_disabled() -> None:
    no_fall = failure_set(BeltThresholds(z_fall=None))
    fallen = state(z=-0.5, s_z=0.03)
    assert not _in(no_fall, fallen)
    fallen[Col.Z] = np.nan
    assert not _in(no_fall, fallen)


@pytest.mark.parametrize("col", [Col.X, Col.Y, Col.Z, Col.SX, Col.SY, Col.SZ, Col.T])
def test_eq_5_9_nan_in_a_read_column_is_failure(col: Col) -> None:
    s = on_tu()
    s[col] = np.nan
    assert _in(FAILURE, s)


def test_eq_5_9_nan_theta_is_not_failure() -> None:
    assert not _in(FAILURE, on_tu(theta=np.nan))


# --- Eq. 5.10: non-terminal set ---------------------------------------------------------


def test_eq_5_10_non_terminal_is_complement_of_terminal_on_random_states() -> None:
    rng = np.random.default_rng(0)
    n = 2000
    states = np.column_stack([
        rng.integers(0, 2, n), rng.uniform(-0.8, 0.7, n), rng.uniform(-0.3, 0.3, n),
        rng.uniform(-0.1, 0.1, n), rng.uniform(0, 0.2, n), rng.uniform(0, 0.15, n),
        rng.uniform(0, 0.05, n), rng.uniform(-np.pi, np.pi, n), rng.integers(0, 2, n),
        rng.integers(0, 3, n), rng.uniform(0, 35, n),
    ])  # fmt: skip
    terminal = SUCCESS.contains(states) | FAILURE.contains(states)
    np.testing.assert_array_equal(non_terminal_set().contains(states), ~terminal)
    assert 0 < terminal.sum() < n
    # S+ and S- meet only through the fall extension (then the outcome is FAILURE, Eq. 5.11)
    both = SUCCESS.contains(states) & FAILURE.contains(states)
    assert np.all(states[both, Col.Z] - states[both, Col.SZ] < -0.03)
    no_fall = failure_set(BeltThresholds(z_fall=None))
    assert not np.any(SUCCESS.contains(states) & no_fall.contains(states))


def test_eq_5_10_t_equal_t_max_is_non_terminal() -> None:
    # Eq. 5.8 needs t < t_max and Eq. 5.9 t > t_max; run_transfer ends such a trace by timeout.
    assert _in(non_terminal_set(), on_tu(t=30.0))


def test_eq_5_10_pre_transfer_states_are_non_terminal() -> None:
    assert _in(non_terminal_set(), state())


# --- bundle and shapes -------------------------------------------------------------------


def test_belt_sets_bundle_forward() -> None:
    sets = belt_sets()
    assert sets.direction is TransferDirection.TM_TO_TU
    assert (sets.a_pre, sets.a_post) == (ASSET_TM, ASSET_TU)
    assert sets.pre == PRE and sets.success == SUCCESS and sets.failure == FAILURE
    assert sets.thresholds == BeltThresholds()


def test_belt_sets_are_vectorised() -> None:
    batch = np.stack([state(), on_tu(), state(x=-0.9)])
    np.testing.assert_array_equal(PRE.contains(batch), [True, False, False])
    np.testing.assert_array_equal(SUCCESS.contains(batch), [False, True, False])
    np.testing.assert_array_equal(FAILURE.contains(batch), [False, False, True])
    assert PRE.contains(batch[0]).shape == ()


def test_belt_sets_reject_wrong_state_dimension() -> None:
    with pytest.raises(InputError, match="d = 11"):
        PRE.contains(np.zeros((2, 10)))


def test_belt_sets_are_picklable() -> None:
    sets = belt_sets()
    clone = pickle.loads(pickle.dumps(sets))
    batch = np.stack([state(), on_tu()])
    np.testing.assert_array_equal(clone.non_terminal.contains(batch), [True, False])
