"""The stepwise transfer process (Eq. 4.11) that `run_transfer` and the controller drive,
and one-state membership through a set's scalar path."""

from __future__ import annotations

import numpy as np
import pytest

from transfertwin import InputError
from transfertwin.ots import (
    NON_TERMINAL,
    BeltThresholds,
    Outcome,
    PredicateSet,
    TransferDirection,
    TransferProcess,
    belt_sets,
    contains_state,
    make_states,
    run_transfer,
)

# The toy OTS of test_run_transfer: state (a, x, t), +0.25 m per transition.
PRE = PredicateSet(lambda s: (s[:, 0] == 0.0) & (s[:, 1] <= 0.0))
SUCCESS = PredicateSet(lambda s: (s[:, 0] == 1.0) & (s[:, 1] >= 1.0))
FAILURE = PredicateSet(lambda s: (s[:, 1] < -1.0) | (s[:, 2] > 3.0))
KW = {"pre": PRE, "success": SUCCESS, "failure": FAILURE, "dt": 0.5, "t_max": 10.0,
      "time_index": 2}  # fmt: skip


def _step(s: np.ndarray) -> np.ndarray:
    x = s[1] + 0.25
    return np.array([1.0 if x > 0.0 else 0.0, x, -99.0])  # the loop overwrites the time


def test_driving_the_process_by_hand_gives_run_transfers_trace() -> None:
    s0 = np.array([0.0, -0.5, 0.0])
    process = TransferProcess(s0, **KW)
    codes = []
    while process.running:
        codes.append(process.advance(_step(process.state)))
    trace = process.trace()
    want = run_transfer(s0, _step, **KW)
    np.testing.assert_array_equal(trace.states, want.states)
    np.testing.assert_array_equal(trace.times, want.times)
    assert trace.outcome is want.outcome is Outcome.SUCCESS
    assert codes == [NON_TERMINAL] * 5 + [1]
    np.testing.assert_array_equal(trace.states[:, 2], 0.5 * np.arange(7))  # the loop clock


def test_fast_forward_ends_at_the_first_terminal_sample_time() -> None:
    s0 = np.array([0.0, -0.5, 0.0])
    process = TransferProcess(s0, **{**KW, "dt": 0.4})
    process.advance(s0.copy())  # the object stays put
    process.fast_forward()
    assert not process.running
    trace = process.trace()
    assert trace.t_end == pytest.approx(3.2)  # the first sample past t > 3 s
    assert trace.outcome is Outcome.FAILURE and not trace.timed_out
    process.fast_forward()  # a finished process stays as it is
    assert process.trace().states.shape == trace.states.shape


def test_a_start_outside_s_pre_is_refused() -> None:
    with pytest.raises(InputError, match=r"Eq\. 4\.8"):
        TransferProcess(np.array([1.0, -0.5, 0.0]), **KW)


def test_contains_state_uses_the_scalar_path_and_agrees_with_the_batch() -> None:
    sets = belt_sets(TransferDirection.TM_TO_TU, BeltThresholds())
    inside = make_states(x=-0.3, y=0.0, s_x=0.05, s_y=0.05)[0]
    outside = make_states(x=0.3, y=0.0, s_x=0.05, s_y=0.05)[0]
    for state in (inside, outside):
        assert contains_state(sets.pre, state) == bool(sets.pre.contains(state))
    assert contains_state(sets.pre, inside) and not contains_state(sets.pre, outside)
    # A set without a scalar path, and a state the scalar path does not take (int dtype).
    assert contains_state(PRE, np.array([0.0, -0.5, 0.0]))
    assert not contains_state(PRE, np.array([1, -1, 0]))
