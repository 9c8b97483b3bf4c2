"""Sec. 4.2, example (c): a delivery robot lowers a box onto a bracket.

State (a, dock_err, z, hooked, contact, t): possessing asset (0 robot,
1 bracket), lateral docking error (m), height of the box hooks above the bracket
seat (m), whether the hooks engage the bracket, whether the box still rests on
the robot's lift, and time (s, written by the loop via ``time_index``).
"""

from __future__ import annotations

import functools

import numpy as np
import pytest

from transfertwin import InputError
from transfertwin.ots import IntersectionSet, Outcome, PossessionSet, PredicateSet, run_transfer

ROBOT, BRACKET = 0.0, 1.0
A, ERR, Z, HOOKED, CONTACT, T = range(6)
MAX_DOCK_ERR = 0.02  # acceptable docking error for a pre-transfer state, m
CLIP_TOL = 0.03  # lateral error the hooks can still catch, m
STEP = 0.03125  # lift travel per transition, m
CLEARANCE = 0.0625  # lift travel below the seat after which contact is lost, m


def lower(s: np.ndarray, *, drift: float = 0.0, step: float = STEP) -> np.ndarray:
    """Lower the lift; the robot may drift sideways by ``drift`` m per step."""
    s = s.copy()
    s[ERR] += drift
    if s[HOOKED] == 1:
        s[Z] -= step  # here z is the lift below the seat; the box hangs on the hooks
        if s[Z] <= -CLEARANCE:
            s[CONTACT], s[A] = 0.0, BRACKET
        return s
    s[Z] -= step
    if s[Z] <= 0.0 and abs(s[ERR]) <= CLIP_TOL:
        s[HOOKED] = 1.0
    return s


PRE = IntersectionSet(
    PossessionSet(ROBOT),
    PredicateSet(
        lambda s: (
            (np.abs(s[:, ERR]) <= MAX_DOCK_ERR)
            & (s[:, CONTACT] == 1)
            & (s[:, HOOKED] == 0)
            & (s[:, Z] > 0)
            & (s[:, T] == 0)
        )
    ),
)
SUCCESS = IntersectionSet(
    PossessionSet(BRACKET), PredicateSet(lambda s: (s[:, HOOKED] == 1) & (s[:, CONTACT] == 0))
)
FAILURE = PredicateSet(lambda s: (s[:, HOOKED] == 0) & (s[:, Z] < 0))  # missed the bracket
SETS = {"pre": PRE, "success": SUCCESS, "failure": FAILURE, "dt": 0.5, "t_max": 10.0}


def _s0(dock_err: float) -> np.ndarray:
    return np.array([ROBOT, dock_err, 0.125, 0.0, 1.0, 0.0])


def test_eq_4_5_box_clips_on_and_possession_changes_on_contact_loss() -> None:
    trace = run_transfer(_s0(0.01), lower, time_index=T, **SETS)
    assert trace.outcome is Outcome.SUCCESS
    contact_lost = trace.states[:, CONTACT] == 0
    np.testing.assert_array_equal(trace.states[:, A] == BRACKET, contact_lost)
    assert trace.t_end == pytest.approx(3.0)
    np.testing.assert_allclose(trace.states[:, T], trace.times)


def test_eq_4_8_docking_error_too_large_is_not_pre_transfer() -> None:
    with pytest.raises(InputError, match=r"Eq\. 4\.8"):
        run_transfer(_s0(0.05), lower, time_index=T, **SETS)


def test_eq_4_6_box_misses_bracket_after_drift() -> None:
    drifting = functools.partial(lower, drift=0.005)
    trace = run_transfer(_s0(0.015), drifting, time_index=T, **SETS)
    assert trace.outcome is Outcome.FAILURE
    assert not trace.timed_out
    assert trace.final_state[A] == ROBOT  # failure before possession changed (Eq. 4.6)


def test_eq_4_9_jammed_lift_times_out() -> None:
    jammed = functools.partial(lower, step=0.0)
    trace = run_transfer(_s0(0.01), jammed, time_index=T, **SETS)
    assert trace.outcome is Outcome.FAILURE
    assert trace.timed_out
    assert trace.t_end == pytest.approx(10.0)
