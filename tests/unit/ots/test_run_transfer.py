"""The generic transfer loop and outcome (Eq. 4.8–4.11, 5.11)."""

from __future__ import annotations

import numpy as np
import pytest

from transfertwin import InputError
from transfertwin.ots import (
    NON_TERMINAL,
    IntersectionSet,
    Outcome,
    PossessionSet,
    PredicateSet,
    ots_outcome,
    outcome_codes,
    run_transfer,
)

# A 1-D toy OTS: state (a, x, t); the object moves +0.25 m per step; possession
# passes from asset 0 to asset 1 at x > 0; success at x >= 1, failure at x < -1.


def _step(s: np.ndarray) -> np.ndarray:
    x = s[1] + 0.25
    return np.array([1.0 if x > 0.0 else 0.0, x, s[2]])


def _stand_still(s: np.ndarray) -> np.ndarray:
    return s.copy()


PRE = IntersectionSet(PossessionSet(0.0), PredicateSet(lambda s: s[:, 1] <= 0.0))
SUCCESS = IntersectionSet(PossessionSet(1.0), PredicateSet(lambda s: s[:, 1] >= 1.0))
FAILURE = PredicateSet(lambda s: s[:, 1] < -1.0)
KW = {"pre": PRE, "success": SUCCESS, "failure": FAILURE, "dt": 0.5, "t_max": 10.0}


def test_eq_4_11_states_follow_the_transition() -> None:
    trace = run_transfer(np.array([0.0, -0.5, 0.0]), _step, **KW)
    np.testing.assert_array_equal(trace.states[:, 1], [-0.5, -0.25, 0.0, 0.25, 0.5, 0.75, 1.0])
    np.testing.assert_array_equal(trace.states[:, 0], [0, 0, 0, 1, 1, 1, 1])
    assert trace.n_transitions == 6


def test_eq_4_9_t_end_is_first_terminal_time() -> None:
    trace = run_transfer(np.array([0.0, -0.5, 0.0]), _step, **KW)
    assert trace.t_end == pytest.approx(3.0)
    np.testing.assert_allclose(trace.times, 0.5 * np.arange(7))
    assert trace.outcome is Outcome.SUCCESS
    assert not trace.timed_out
    np.testing.assert_array_equal(trace.final_state, [1.0, 1.0, 0.0])


def test_eq_4_8_s0_outside_pre_raises() -> None:
    with pytest.raises(InputError, match=r"Eq\. 4\.8"):
        run_transfer(np.array([1.0, -0.5, 0.0]), _step, **KW)


def test_eq_4_8_s0_must_be_a_single_state() -> None:
    with pytest.raises(InputError, match=r"Eq\. 4\.8"):
        run_transfer(np.zeros((2, 3)), _step, **KW)


def test_eq_4_9_terminal_s0_ends_at_t0_without_calling_u() -> None:
    def never(s: np.ndarray) -> np.ndarray:
        raise AssertionError("u must not be applied to a terminal state (Eq. 4.10)")

    trace = run_transfer(np.array([0.0, -2.0, 0.0]), never, **KW)
    assert trace.states.shape == (1, 3)
    assert trace.t_end == 0.0
    assert trace.outcome is Outcome.FAILURE


def test_eq_4_10_u_is_only_applied_to_non_terminal_states() -> None:
    seen: list[float] = []

    def recording(s: np.ndarray) -> np.ndarray:
        seen.append(float(s[1]))
        return _step(s)

    run_transfer(np.array([0.0, -0.5, 0.0]), recording, **KW)
    assert seen == [-0.5, -0.25, 0.0, 0.25, 0.5, 0.75]


def test_timeout_is_failure_and_flagged() -> None:
    trace = run_transfer(np.array([0.0, -0.5, 0.0]), _stand_still, **KW)
    assert trace.outcome is Outcome.FAILURE
    assert trace.timed_out
    assert trace.t_end == pytest.approx(10.0)
    assert trace.states.shape == (21, 3)


def test_timeout_with_inexact_dt_stops_at_t_max() -> None:
    trace = run_transfer(
        np.array([0.0, -0.5, 0.0]), _stand_still, **{**KW, "dt": 0.1, "t_max": 3.0}
    )
    assert trace.states.shape == (31, 3)
    assert trace.t_end == pytest.approx(3.0)


def test_max_steps_caps_the_loop() -> None:
    trace = run_transfer(np.array([0.0, -0.5, 0.0]), _stand_still, max_steps=4, **KW)
    assert trace.n_transitions == 4
    assert trace.timed_out


def test_time_index_makes_the_loop_the_clock() -> None:
    trace = run_transfer(np.array([0.0, -0.5, 2.0]), _step, time_index=2, **{**KW, "t_max": 12})
    np.testing.assert_allclose(trace.states[:, 2], 2.0 + 0.5 * np.arange(7))
    np.testing.assert_allclose(trace.times, trace.states[:, 2])
    assert trace.t_end == pytest.approx(5.0)


def test_trace_arrays_are_read_only() -> None:
    trace = run_transfer(np.array([0.0, -0.5, 0.0]), _step, **KW)
    with pytest.raises(ValueError):
        trace.states[0, 0] = 5.0
    with pytest.raises(ValueError):
        trace.times[0] = 5.0


def test_s0_is_not_modified() -> None:
    s0 = np.array([0.0, -0.5, 0.0])
    run_transfer(s0, _step, time_index=2, **KW)
    np.testing.assert_array_equal(s0, [0.0, -0.5, 0.0])


def test_u_with_wrong_output_shape_raises() -> None:
    with pytest.raises(InputError, match=r"Eq\. 4\.10"):
        run_transfer(np.array([0.0, -0.5, 0.0]), lambda s: s[:2], **KW)


@pytest.mark.parametrize(
    ("dt", "t_max", "max_steps"),
    [(0.0, 10.0, None), (-1.0, 10.0, None), (np.nan, 10.0, None), (0.5, 0.0, None),
     (0.5, np.inf, None), (0.5, 10.0, 0), (0.5, 10.0, True), (0.5, 10.0, 2.0)],
)  # fmt: skip
def test_invalid_clock_raises(dt: float, t_max: float, max_steps: object) -> None:
    kw = {**KW, "dt": dt, "t_max": t_max}
    with pytest.raises(InputError):
        run_transfer(np.array([0.0, -0.5, 0.0]), _step, max_steps=max_steps, **kw)


def test_time_index_out_of_range_raises() -> None:
    with pytest.raises(InputError, match="time_index"):
        run_transfer(np.array([0.0, -0.5, 0.0]), _step, time_index=3, **KW)


def test_eq_5_11_outcome_values_are_one_and_zero() -> None:
    assert Outcome.SUCCESS.value == 1 and int(Outcome.SUCCESS) == 1
    assert Outcome.FAILURE.value == 0 and int(Outcome.FAILURE) == 0
    assert Outcome(1) is Outcome.SUCCESS


def test_eq_5_11_ots_outcome_of_terminal_states() -> None:
    assert ots_outcome([1.0, 1.5, 0.0], SUCCESS, FAILURE) is Outcome.SUCCESS
    assert ots_outcome([0.0, -1.5, 0.0], SUCCESS, FAILURE) is Outcome.FAILURE


def test_eq_5_11_failure_wins_when_a_state_is_in_both_sets() -> None:
    overlapping_failure = PredicateSet(lambda s: s[:, 1] > 1.25)
    assert ots_outcome([1.0, 1.5, 0.0], SUCCESS, overlapping_failure) is Outcome.FAILURE
    trace = run_transfer(
        np.array([0.0, -0.5, 0.0]),
        lambda s: np.array([1.0, s[1] + 2.0, 0.0]),
        **{**KW, "failure": overlapping_failure},
    )
    assert trace.final_state[1] == 1.5
    assert trace.outcome is Outcome.FAILURE


def test_eq_5_11_non_terminal_state_has_no_outcome() -> None:
    with pytest.raises(InputError, match=r"Eq\. 5\.11"):
        ots_outcome([0.0, 0.0, 0.0], SUCCESS, FAILURE)


def test_eq_5_11_outcome_codes_vectorised() -> None:
    states = np.array([[1.0, 1.5, 0.0], [0.0, -1.5, 0.0], [0.0, 0.0, 0.0]])
    codes = outcome_codes(states, SUCCESS, FAILURE)
    np.testing.assert_array_equal(codes, [1, 0, NON_TERMINAL])
    assert outcome_codes(states[0], SUCCESS, FAILURE).shape == ()


def test_early_stop_ends_where_the_loop_run_to_the_end_would() -> None:
    # A failure set with a time limit (as the belt sets' t > t_max): a stalled state
    # fast-forwarded by `stop` ends at the first sample past that limit, the sample at
    # which the loop without `stop` ends, with the same outcome.
    timed_failure = PredicateSet(lambda s: (s[:, 1] < -1.0) | (s[:, 2] > 3.0))
    # The controller's loop limit is t_max + dt; with dt = 0.4 the loop's last sample
    # (3.6 s) lies beyond the first one past 3 s (3.2 s).
    kw = {**KW, "failure": timed_failure, "dt": 0.4, "t_max": 3.0 + 0.4, "time_index": 2}
    s0 = np.array([0.0, -0.5, 0.0])
    full = run_transfer(s0, _stand_still, **kw)
    calls = []
    early = run_transfer(s0, _stand_still, stop=lambda s: calls.append(s) or True, **kw)
    assert len(calls) == 1  # stopped after one transition
    assert early.t_end == full.t_end == pytest.approx(3.2)
    assert early.outcome is full.outcome is Outcome.FAILURE
    np.testing.assert_array_equal(early.final_state, full.final_state)
