"""Transfer process and outcome of a generic OTS (Eq. 4.8–4.11, 5.11).

`run_transfer` iterates a pure state transition function ``u`` (Eq. 4.10) from
a pre-transfer state until the first terminal state (Eq. 4.9) or a timeout;
`TransferProcess` is that loop one transition at a time, for a caller that makes each
new state itself (a controller stepping a plant).

Decisions the equations leave open:

* **Overlap of S+ and S-.** Eq. 5.11 assumes the two sets are disjoint. Where a
  state is in both, the outcome is FAILURE: a success must be free of any
  failure condition (e.g. an object that lies inside the receiver's belt area
  but has fallen below the belt surface).
* **Clock.** The loop owns the clock: state ``i`` is at ``t_i = t0 + i * dt``.
  With ``time_index`` set, ``t0`` is read from ``s0`` and ``t_i`` is written into
  that component of every new state, overwriting whatever ``u`` put there, so
  sets that read time (``t < t_max`` in Eq. 5.8) see the loop clock.
* **Timeout.** If no terminal state is reached by ``t_max`` (or after
  ``max_steps`` transitions), the trace ends at the last state with outcome
  FAILURE and ``timed_out=True``. This also closes the gap between ``t < t_max``
  (Eq. 5.8) and ``t > t_max`` (Eq. 5.9): a state at exactly ``t_max`` that is
  neither success nor failure ends the transfer as a failure.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from enum import Enum

import numpy as np
from numpy.typing import ArrayLike

from transfertwin._errors import InputError
from transfertwin.ots._sets import StateSet, as_state_batch

__all__ = [
    "NON_TERMINAL",
    "Outcome",
    "TransferProcess",
    "TransferTrace",
    "Transition",
    "contains_state",
    "ots_outcome",
    "outcome_codes",
    "run_transfer",
]

#: Code used by `outcome_codes` for a state in neither S+ nor S- (Eq. 4.7).
NON_TERMINAL = -1

#: A pure state transition ``u: S' -> S_o`` (Eq. 4.10); maps ``(d,)`` to ``(d,)``.
Transition = Callable[[np.ndarray], np.ndarray]


class Outcome(Enum):
    """Result of an object transfer, valued as in Eq. 5.11 (1 success, 0 failure)."""

    SUCCESS = 1
    FAILURE = 0

    def __int__(self) -> int:
        return int(self.value)


def _takes_one(states: object, state_set: StateSet) -> bool:
    """Whether `states` is one float64 state the set's `contains_one` fast path handles."""
    return (
        isinstance(states, np.ndarray)
        and states.ndim == 1
        and states.dtype == np.float64
        and states.shape[0] == getattr(state_set, "one_dim", None)
    )


def _scalar_path(states: object, success: StateSet, failure: StateSet) -> bool:
    """Whether `states` is one float64 state both sets' `contains_one` fast path handles."""
    return _takes_one(states, success) and _takes_one(states, failure)


def contains_state(states: StateSet, state: np.ndarray) -> bool:
    """Whether one float state ``(d,)`` is in `states`: through the set's scalar
    `contains_one` where it has one for this length, else its batched `contains`."""
    if _takes_one(state, states):
        return bool(states.contains_one(state))  # type: ignore[attr-defined]
    return bool(states.contains(state))


def _code_one(state: np.ndarray, success: StateSet, failure: StateSet) -> int:
    """Scalar fast path of `outcome_codes` for sets that offer `contains_one` (e.g. the
    belt sets): same result as the batch path, without its array overhead per sample."""
    return 0 if failure.contains_one(state) else (1 if success.contains_one(state) else -1)


def outcome_codes(states: ArrayLike, success: StateSet, failure: StateSet) -> np.ndarray:
    """Outcome code of each state (vectorised Eq. 5.11).

    Args:
        states: Batch ``(N, d)`` or one state ``(d,)``.
        success: Success set S+ (Eq. 4.5).
        failure: Failure set S- (Eq. 4.6).

    Returns:
        int8 array ``(N,)`` (or shape ``()``): 1 for S+ \\ S-, 0 for S-, and
        `NON_TERMINAL` (-1) for the non-terminal states S' (Eq. 4.7).
    """
    if _scalar_path(states, success, failure):
        return np.array(_code_one(states, success, failure), dtype=np.int8)
    batch, single = as_state_batch(states)
    codes = np.full(batch.shape[0], NON_TERMINAL, dtype=np.int8)
    codes[success.contains(batch)] = 1
    codes[failure.contains(batch)] = 0
    return codes.reshape(()) if single else codes


def ots_outcome(state: ArrayLike, success: StateSet, failure: StateSet) -> Outcome:
    """Outcome of a terminal state (Eq. 5.11); failure wins if in both sets.

    Args:
        state: One state ``(d,)``.
        success: Success set S+ (Eq. 4.5).
        failure: Failure set S- (Eq. 4.6).

    Returns:
        `Outcome.FAILURE` if the state is in S-, else `Outcome.SUCCESS` if in S+.

    Raises:
        InputError: If the state is not a single ``(d,)`` vector or is non-terminal.
    """
    batch, single = as_state_batch(state)
    if not single:
        raise InputError(f"expected one state (d,), got shape {batch.shape} (Eq. 5.11)")
    code = int(outcome_codes(batch, success, failure)[0])
    if code == NON_TERMINAL:
        raise InputError("the state is non-terminal (in neither S+ nor S-) (Eq. 5.11)")
    return Outcome(code)


@dataclass(frozen=True, eq=False)
class TransferTrace:
    """A discrete transfer process s[t_0], ..., s[t_end] (Eq. 4.11).

    Attributes:
        states: Read-only float array ``(n, d)``; row 0 is the pre-transfer state.
        times: Read-only float array ``(n,)`` of sample times in seconds.
        t_end: Time of the last state in seconds (Eq. 4.9, or the timeout).
        outcome: Outcome of the last state (Eq. 5.11); FAILURE on timeout.
        timed_out: True if the trace ended without reaching S+ ∪ S-.
    """

    states: np.ndarray
    times: np.ndarray
    t_end: float
    outcome: Outcome
    timed_out: bool

    @property
    def final_state(self) -> np.ndarray:
        """The last state, shape ``(d,)``."""
        return self.states[-1]

    @property
    def n_transitions(self) -> int:
        """Number of applications of ``u``."""
        return self.states.shape[0] - 1


def _check_clock(dt: float, t0: float, t_max: float, max_steps: int | None) -> None:
    if not (math.isfinite(dt) and dt > 0.0):
        raise InputError(f"dt must be a positive finite number of seconds, got {dt}")
    if not (math.isfinite(t0) and math.isfinite(t_max) and t_max > t0):
        raise InputError(f"t_max must be finite and after t0 = {t0} s, got {t_max}")
    if max_steps is not None and (
        isinstance(max_steps, bool) or not isinstance(max_steps, int) or max_steps < 1
    ):
        raise InputError(f"max_steps must be a positive integer or None, got {max_steps!r}")


def _apply(u: Transition, state: np.ndarray) -> np.ndarray:
    try:
        new = np.array(u(state.copy()), dtype=float)
    except (TypeError, ValueError) as exc:
        raise InputError(f"u must return a numeric state: {exc} (Eq. 4.10)") from None
    if new.shape != state.shape:
        raise InputError(f"u must return shape {state.shape}, got {new.shape} (Eq. 4.10)")
    return new


def _first_terminal_index(
    state: np.ndarray, i: int, n_max: int, t0: float, dt: float, time_index: int | None,
    success: StateSet, failure: StateSet,
) -> int:  # fmt: skip
    """First index in (i, n_max] at which `state`, its time set to t0 + index·dt, is
    terminal; n_max if none is (one batched set evaluation)."""
    if time_index is None or n_max <= i:
        return n_max
    later = np.repeat(state[None, :], n_max - i, axis=0)
    later[:, time_index] = t0 + dt * np.arange(i + 1, n_max + 1, dtype=float)
    terminal = np.flatnonzero(outcome_codes(later, success, failure) != NON_TERMINAL)
    return i + 1 + int(terminal[0]) if terminal.size else n_max


class TransferProcess:
    """The discrete transfer process of Eq. 4.11, one transition at a time.

    `run_transfer` drives it with a transition function; a controller that produces each
    new state itself (by stepping a plant and observing it) drives it directly, without
    wrapping that work in a function of the previous state. Either way the clock, the
    termination (Eq. 4.9), the timeout and the early timeout are decided here.

    Args:
        s0: Pre-transfer state ``(d,)``; must be in ``pre`` (Eq. 4.8).
        pre, success, failure: S_pre, S+ and S- (Eq. 4.4–4.6).
        dt: Time step in seconds (> 0).
        t_max: Timeout in seconds on the loop clock (absolute, > t0).
        time_index: Component of the state that holds time in seconds, or ``None`` if
            the state has no time (then ``t0 = 0``).
        max_steps: Optional cap on the number of transitions.

    Raises:
        InputError: If ``s0`` is not a pre-transfer state or the clock parameters are
            invalid.
    """

    def __init__(
        self,
        s0: ArrayLike,
        *,
        pre: StateSet,
        success: StateSet,
        failure: StateSet,
        dt: float,
        t_max: float,
        time_index: int | None = None,
        max_steps: int | None = None,
    ) -> None:
        batch, single = as_state_batch(s0)
        if not single:
            raise InputError(f"s0 must be one state (d,), got shape {batch.shape} (Eq. 4.8)")
        state = batch[0].copy()
        d = state.shape[0]
        if time_index is not None and not -d <= time_index < d:
            raise InputError(f"time_index {time_index} is out of range for d = {d}")
        self.t0 = float(state[time_index]) if time_index is not None else 0.0
        _check_clock(dt, self.t0, t_max, max_steps)
        if not contains_state(pre, state):
            raise InputError("s0 is not a pre-transfer state (not in S_pre) (Eq. 4.8)")
        n_max = max(1, math.ceil((t_max - self.t0) / dt - 1e-9))
        self.n_max = min(n_max, max_steps) if max_steps is not None else n_max
        self.dt, self.time_index = dt, time_index
        self.success, self.failure = success, failure
        self.state = state  # the latest state s[t_i]
        self.i = 0  # transitions so far
        self._states = [state]
        self._steps = [0]  # transition index of each state (its time is t0 + index * dt)
        self._scalar = _scalar_path(state, success, failure)  # every later state has its shape
        self.code = int(outcome_codes(state, success, failure))

    @property
    def running(self) -> bool:
        """Whether the latest state is non-terminal and the timeout is not reached."""
        return self.code == NON_TERMINAL and self.i < self.n_max

    def advance(self, new: np.ndarray) -> int:
        """Append the next state (Eq. 4.10's u(s)) and return its outcome code (1, 0 or
        `NON_TERMINAL`). `new` must be a fresh float array ``(d,)``: the process keeps it
        and writes the loop clock into its time component."""
        self.i += 1
        if self.time_index is not None:
            new[self.time_index] = self.t0 + self.i * self.dt
        self.state = new
        self._states.append(new)
        self._steps.append(self.i)
        if self._scalar:
            self.code = _code_one(new, self.success, self.failure)
        else:
            self.code = int(outcome_codes(new, self.success, self.failure))
        return self.code

    def fast_forward(self) -> None:
        """End now for a state that stays put (an early timeout): the latest state is carried
        forward to the first later sample time ``t0 + n·dt`` at which it is in S+ ∪ S-
        (for the belt sets: the first sample after t_max, as a loop run to the end gives),
        or to the last one."""
        if not self.running:
            return
        i = _first_terminal_index(
            self.state, self.i, self.n_max, self.t0, self.dt, self.time_index,
            self.success, self.failure,
        )  # fmt: skip
        state = self.state.copy()
        if self.time_index is not None:
            state[self.time_index] = self.t0 + i * self.dt
        self.i, self.state = i, state
        self._states.append(state)
        self._steps.append(i)
        self.code = int(outcome_codes(state, self.success, self.failure))
        self.n_max = i  # nothing follows

    def trace(self) -> TransferTrace:
        """The trace so far (Eq. 4.11); FAILURE with ``timed_out`` if it did not end in
        S+ ∪ S-."""
        times = self.t0 + self.dt * np.asarray(self._steps, dtype=float)
        # One concatenation of the (d,) rows: np.stack's checks cost more than the copy.
        stacked = np.concatenate(self._states).reshape(len(self._states), -1)
        stacked.setflags(write=False)
        times.setflags(write=False)
        timed_out = self.code == NON_TERMINAL
        return TransferTrace(
            states=stacked,
            times=times,
            t_end=float(times[-1]),
            outcome=Outcome.FAILURE if timed_out else Outcome(self.code),
            timed_out=timed_out,
        )


def run_transfer(
    s0: ArrayLike,
    u: Transition,
    *,
    pre: StateSet,
    success: StateSet,
    failure: StateSet,
    dt: float,
    t_max: float,
    time_index: int | None = None,
    max_steps: int | None = None,
    stop: Callable[[np.ndarray], bool] | None = None,
) -> TransferTrace:
    """Run the discrete transfer process of Eq. 4.11 to its end (Eq. 4.9).

    Args:
        s0: Pre-transfer state ``(d,)``; must be in ``pre`` (Eq. 4.8).
        u: Pure transition ``(d,) -> (d,)`` (Eq. 4.10); applied only to
            non-terminal states. It receives a copy and may not keep it.
        pre: Pre-transfer set S_pre (Eq. 4.4).
        success: Success set S+ (Eq. 4.5).
        failure: Failure set S- (Eq. 4.6).
        dt: Time step in seconds (> 0).
        t_max: Timeout in seconds on the loop clock (absolute, > t0).
        time_index: Component of the state that holds time in seconds, or
            ``None`` if the state has no time (then ``t0 = 0``).
        max_steps: Optional cap on the number of transitions.
        stop: Optional early timeout: called with each new non-terminal state; True
            means the state will not change before the timeout (e.g. a stuck object),
            so the trace ends now as the loop would end at the timeout
            (`TransferProcess.fast_forward`).

    Returns:
        The trace, ending at the first state in S+ ∪ S- or at the timeout.

    Raises:
        InputError: If ``s0`` is not a pre-transfer state, the clock parameters
            are invalid, or ``u`` returns a malformed state.
    """
    process = TransferProcess(
        s0, pre=pre, success=success, failure=failure, dt=dt, t_max=t_max,
        time_index=time_index, max_steps=max_steps,
    )  # fmt: skip
    while process.running:
        process.advance(_apply(u, process.state))
        if stop is not None and process.running and stop(process.state.copy()):
            process.fast_forward()
    return process.trace()
