"""The transfer process (Eq. 4.8–4.11) and the outcome codes (Eq. 5.11) where the scalar fast
path and the batch path meet: a batch of exactly eleven states (the belt state's length), a
belt success set beside a generic failure set, the int8 codes of both paths; the clock's
edges (one transition when t_max is within one step, a start time other than 0, a negative
time index); an early timeout that finds no terminal sample before the last one; and the
generic sets' one-component states (Eq. 4.1).
"""

from __future__ import annotations

import numpy as np
import pytest

from transfertwin._errors import InputError
from transfertwin.ots import (
    BeltThresholds,
    Col,
    PossessionSet,
    PredicateSet,
    TransferDirection,
    UnionSet,
    belt_sets,
    make_states,
    outcome_codes,
    run_transfer,
)
from transfertwin.ots._model import contains_state

SETS = belt_sets(TransferDirection.TM_TO_TU, BeltThresholds())


def _eleven_states() -> np.ndarray:
    x = np.array([-0.3, 0.3, 0.3, 0.9, -0.3, 0.3, 0.1, 0.3, -0.3, 0.3, 0.45])
    t = np.array([0.0, 5.0, 31.0, 5.0, 5.0, 5.0, 5.0, np.nan, 0.0, 29.0, 5.0])
    a = np.array([0, 1, 1, 1, 0, 1, 1, 1, 0, 1, 1])
    return make_states(a=a, x=x, y=0.0, s_x=0.05, s_y=0.05, z=0.05, s_z=0.05, t=t)


def test_eq_5_11_a_batch_of_eleven_states_is_a_batch_not_one_state() -> None:
    states = _eleven_states()
    assert states.shape == (11, 11)
    codes = outcome_codes(states, SETS.success, SETS.failure)
    assert codes.shape == (11,) and codes.dtype == np.int8
    one = [outcome_codes(s, SETS.success, SETS.failure) for s in states]
    assert all(c.shape == () and c.dtype == np.int8 for c in one)
    assert codes.tolist() == [int(c) for c in one] == [-1, 1, 0, 0, -1, 1, -1, 0, -1, 1, 1]


def test_eq_5_11_belt_success_beside_a_generic_failure_set_uses_the_batch_path() -> None:
    failure = UnionSet(PredicateSet(lambda s: s[:, Col.T] > 30.0, dim=11))
    states = _eleven_states()
    codes = [int(outcome_codes(s, SETS.success, failure)) for s in states]
    assert codes == outcome_codes(states, SETS.success, failure).tolist()
    assert codes[2] == 0 and codes[1] == 1
    assert contains_state(failure, states[2]) and not contains_state(failure, states[1])


def _run(s0, **kw):
    pre = PredicateSet(lambda s: np.ones(len(s), bool), dim=2)
    never = PredicateSet(lambda s: np.zeros(len(s), bool), dim=2)
    return run_transfer(s0, lambda s: s, pre=pre, success=never, failure=never, **kw)


def test_eq_4_11_one_transition_when_t_max_is_within_one_step() -> None:
    trace = _run(np.array([0.0, 0.0]), dt=1.0, t_max=0.5, time_index=1)
    assert trace.n_transitions == 1 and trace.t_end == 1.0 and trace.timed_out


def test_eq_4_11_the_clock_starts_at_the_state_time() -> None:
    trace = _run(np.array([0.0, 2.0]), dt=0.5, t_max=3.0, time_index=1)
    assert trace.times.tolist() == [2.0, 2.5, 3.0]
    assert trace.states[:, 1].tolist() == [2.0, 2.5, 3.0]


def test_eq_4_11_a_negative_time_index_counts_from_the_end() -> None:
    trace = _run(np.array([1.0, 0.0]), dt=0.5, t_max=1.5, time_index=-2)
    assert trace.states[:, 0].tolist() == [1.0, 1.5] and trace.t_end == 1.5
    with pytest.raises(InputError, match="out of range"):
        _run(np.array([1.0, 0.0]), dt=0.5, t_max=1.0, time_index=-3)


def test_eq_4_11_early_timeout_without_a_terminal_sample_ends_at_the_last_one() -> None:
    """The sets' t_max equals the loop's: the last sample is at t_max exactly, which is
    neither success (t < t_max) nor failure (t > t_max)."""
    s0 = make_states(x=-0.3, y=0.0, s_x=0.05, s_y=0.05, z=0.05, s_z=0.05)[0]
    kw = dict(pre=SETS.pre, success=SETS.success, failure=SETS.failure, dt=0.5, t_max=30.0,
              time_index=int(Col.T))  # fmt: skip
    full = run_transfer(s0, lambda s: s, **kw)
    fast = run_transfer(s0, lambda s: s, stop=lambda s: True, **kw)
    assert full.timed_out and fast.timed_out
    assert fast.t_end == full.t_end == 30.0 and fast.n_transitions == 2


def test_eq_4_1_a_state_of_component_0_alone_is_a_state() -> None:
    owned = PossessionSet(1.0)
    assert owned.contains(np.array([1.0])).shape == ()
    assert owned.contains(np.array([[1.0], [0.0]])).tolist() == [True, False]
    with pytest.raises(InputError, match="at least component 0"):
        owned.contains(np.zeros((2, 0)))


def test_eq_4_11_early_timeout_without_a_time_component() -> None:
    trace = _run(np.array([0.0, 0.0]), dt=0.5, t_max=2.0, stop=lambda s: True)
    assert trace.timed_out and trace.times.tolist() == [0.0, 0.5, 2.0]
    assert trace.t_end == 2.0 and trace.n_transitions == 2
