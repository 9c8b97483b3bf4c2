"""Sec. 4.2, example (b): pick & place as two concatenated OTS.

State (a, x, z, gripper_z, closed, grasped): possessing asset (0 shelf,
1 manipulator), object position x along the shelf and height z above the shelf
board (m), gripper height (m), whether the gripper is closed and whether it holds
the object. OTS 1 moves the object shelf -> manipulator; its success set is the
pre-transfer set of OTS 2, manipulator -> shelf slot.
"""

from __future__ import annotations

import functools

import numpy as np
import pytest

from transfertwin import InputError
from transfertwin.ots import IntersectionSet, Outcome, PossessionSet, PredicateSet, run_transfer

SHELF, MANIP = 0.0, 1.0
A, X, Z, GRIP_Z, CLOSED, GRASPED = range(6)
STEP = 0.0625  # gripper travel per transition, m
LIFT = 0.125  # lift height that completes the pick, m
SOURCE_SLOT = (0.0, 0.125)
TARGET_SLOT = (0.5, 0.625)
CLOCK = {"dt": 0.5, "t_max": 20.0}


def pick(s: np.ndarray, *, grasp_ok: bool = True) -> np.ndarray:
    """Lower, close, lift; possession passes when the object leaves the shelf."""
    s = s.copy()
    if s[CLOSED] == 0 and s[GRIP_Z] > 0:
        s[GRIP_Z] = max(0.0, s[GRIP_Z] - STEP)
    elif s[CLOSED] == 0:
        s[CLOSED], s[GRASPED] = 1.0, float(grasp_ok)
    else:
        s[GRIP_Z] += STEP
        if s[GRASPED] == 1:
            s[Z] = s[GRIP_Z]
            s[A] = MANIP
    return s


def place(s: np.ndarray, *, x_goal: float = 0.5625) -> np.ndarray:
    """Move to x_goal, lower, open; possession passes on release."""
    s = s.copy()
    if s[X] != x_goal:
        s[X] = min(s[X] + STEP, x_goal) if s[X] < x_goal else max(s[X] - STEP, x_goal)
    elif s[Z] > 0:
        s[Z] = s[GRIP_Z] = max(0.0, s[Z] - STEP)
    else:
        s[CLOSED], s[GRASPED], s[A] = 0.0, 0.0, SHELF
    return s


def _in_slot(s: np.ndarray, slot: tuple[float, float]) -> np.ndarray:
    return (s[:, X] >= slot[0]) & (s[:, X] <= slot[1])


def _resting_free(s: np.ndarray) -> np.ndarray:
    return (s[:, Z] == 0) & (s[:, GRASPED] == 0)


PICK_PRE = IntersectionSet(
    PossessionSet(SHELF),
    PredicateSet(lambda s: _resting_free(s) & (s[:, CLOSED] == 0) & _in_slot(s, SOURCE_SLOT)),
)
PICK_SUCCESS = IntersectionSet(
    PossessionSet(MANIP), PredicateSet(lambda s: (s[:, GRASPED] == 1) & (s[:, Z] >= LIFT))
)
PICK_FAILURE = PredicateSet(  # lifted with an empty gripper
    lambda s: (s[:, CLOSED] == 1) & (s[:, GRASPED] == 0) & (s[:, GRIP_Z] >= LIFT)
)
PLACE_PRE = PICK_SUCCESS  # the success states of OTS 1 are the pre-transfer states of OTS 2
PLACE_SUCCESS = IntersectionSet(
    PossessionSet(SHELF), PredicateSet(lambda s: _resting_free(s) & _in_slot(s, TARGET_SLOT))
)
PLACE_FAILURE = PredicateSet(lambda s: (s[:, GRASPED] == 0) & ~_in_slot(s, TARGET_SLOT))

PICK = {"pre": PICK_PRE, "success": PICK_SUCCESS, "failure": PICK_FAILURE, **CLOCK}
PLACE = {"pre": PLACE_PRE, "success": PLACE_SUCCESS, "failure": PLACE_FAILURE, **CLOCK}
S0 = np.array([SHELF, 0.0625, 0.0, 0.125, 0.0, 0.0])


def test_eq_4_5_pick_then_place_concatenates_two_ots() -> None:
    first = run_transfer(S0, pick, **PICK)
    assert first.outcome is Outcome.SUCCESS
    assert first.final_state[A] == MANIP
    second = run_transfer(first.final_state, place, **PLACE)
    assert second.outcome is Outcome.SUCCESS
    np.testing.assert_array_equal(second.final_state, [SHELF, 0.5625, 0.0, 0.0, 0.0, 0.0])


def test_eq_4_2_possession_changes_when_object_leaves_shelf() -> None:
    trace = run_transfer(S0, pick, **PICK)
    lifted = trace.states[:, Z] > 0
    np.testing.assert_array_equal(trace.states[:, A] == MANIP, lifted)


def test_eq_4_6_missed_grasp_fails_and_blocks_the_second_ots() -> None:
    first = run_transfer(S0, functools.partial(pick, grasp_ok=False), **PICK)
    assert first.outcome is Outcome.FAILURE
    assert not first.timed_out
    with pytest.raises(InputError, match=r"Eq\. 4\.8"):
        run_transfer(first.final_state, place, **PLACE)


def test_eq_4_6_misplaced_object_fails_the_second_ots() -> None:
    first = run_transfer(S0, pick, **PICK)
    second = run_transfer(first.final_state, functools.partial(place, x_goal=0.8125), **PLACE)
    assert second.outcome is Outcome.FAILURE
    assert second.final_state[A] == SHELF  # released, but outside the slot
