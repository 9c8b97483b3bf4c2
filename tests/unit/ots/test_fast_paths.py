"""Scalar set membership equals the batch path; the early-timeout hook of run_transfer."""

from __future__ import annotations

import numpy as np

from transfertwin.ots import (
    BeltThresholds,
    TransferDirection,
    belt_sets,
    make_states,
    outcome_codes,
    run_transfer,
)


def _random_states(n: int = 3000) -> np.ndarray:
    rng = np.random.default_rng(0)
    cols = [rng.integers(0, 2, n), rng.uniform(-0.8, 0.7, n), rng.uniform(-0.3, 0.3, n),
            rng.uniform(-0.1, 0.1, n), rng.uniform(0, 0.2, n), rng.uniform(0, 0.2, n),
            rng.uniform(0, 0.1, n), rng.uniform(-3, 3, n), rng.integers(0, 2, n),
            rng.integers(0, 3, n), rng.choice([0.0, 1e-10, 1.0, 30.0, 30.1], n)]  # fmt: skip
    states = np.column_stack(cols).astype(float)
    states[rng.random(n) < 0.05, 3] = np.nan
    return states


def test_scalar_membership_equals_batch():
    states = _random_states()
    for direction in TransferDirection:
        sets = belt_sets(direction, BeltThresholds())
        for s in (sets.pre, sets.success, sets.failure):
            assert (s.contains(states) == [s.contains_one(x) for x in states]).all()
        batch = outcome_codes(states, sets.success, sets.failure)
        assert (batch == [int(outcome_codes(x, sets.success, sets.failure)) for x in states]).all()


def test_stop_hook_fast_forwards_to_the_timeout():
    sets = belt_sets(TransferDirection.TM_TO_TU, BeltThresholds(t_max=5.0))
    s0 = make_states(x=-0.3, y=0.0, s_x=0.05, s_y=0.05)[0]
    calls = []

    def u(s):
        calls.append(1)
        return s  # the object never moves

    kw = dict(pre=sets.pre, success=sets.success, failure=sets.failure, dt=0.1, t_max=5.1,
              time_index=10)  # fmt: skip
    full = run_transfer(s0, u, **kw)
    n_full = len(calls)
    calls.clear()
    fast = run_transfer(s0, u, stop=lambda s: s[10] >= 1.0 - 1e-9, **kw)
    assert len(calls) < n_full / 4
    assert fast.outcome is full.outcome and fast.timed_out == full.timed_out
    assert fast.t_end == full.t_end
    np.testing.assert_array_equal(fast.final_state, full.final_state)
