"""The OTS controller: one object transfer between two belt units (Sec. 5.4).

The same code drives a physical pair of units and their virtual models; it only talks to
the `UnitHAL`, `ObjectSensor` and `Clock` protocols. A transfer is the generic loop of
Eq. 4.11 (`transfertwin.ots.run_transfer`) whose transition u is "let one camera period
pass with the belts running, then observe", evaluated against the belt system's sets
(Eq. 5.7–5.10).
"""

from __future__ import annotations

import functools
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from transfertwin.control._hal import Clock, ObjectSensor, UnitHAL
from transfertwin.ots import (
    N_COLS,
    BeltSets,
    BeltThresholds,
    Col,
    Conveyor,
    Face,
    Outcome,
    TransferDirection,
    TransferProcess,
    TransferTrace,
    belt_sets,
    contains_state,
    conveyor_of,
)

_X, _Y, _Z = int(Col.X), int(Col.Y), int(Col.Z)
_F, _C, _T = int(Col.F), int(Col.C), int(Col.T)


@functools.lru_cache(maxsize=16)
def _sets(direction: TransferDirection, thresholds: BeltThresholds) -> BeltSets:
    """`belt_sets`, built once per direction and thresholds (frozen, so shareable)."""
    return belt_sets(direction, thresholds)


@functools.cache
def _codes(face: str, conveyor: str) -> tuple[int, int]:
    """State codes of face f and conveyor c (Eq. 5.4)."""
    return int(Face[face.upper()]), int(Conveyor[conveyor.upper()])


__all__ = ["STALL_MODES", "OTSController", "TransferRecord", "belts_for"]


def belts_for(conveyor: str) -> tuple[str, ...]:
    """The belts that conveyor position c runs (Eq. 5.6): left, right or both."""
    return ("left", "right") if conveyor == "both" else (conveyor,)


@dataclass(frozen=True)
class TransferRecord:
    """What one OTS did.

    Attributes:
        direction: TM → TU or TU → TM.
        conveyor: Conveyor position c that was driven ('left', 'right', 'both').
        valid: False if the observed initial state was not a pre-transfer state.
        start_state: The observed state at t_0, (11,) (Eq. 5.4).
        trace: The state sequence (Eq. 4.11), None when not valid.
    """

    direction: TransferDirection
    conveyor: str
    valid: bool
    start_state: np.ndarray
    trace: TransferTrace | None

    @property
    def y(self) -> int:
        """Binary OTS result (Eq. 5.11); 0 for an invalid start."""
        return int(self.trace is not None and self.trace.outcome is Outcome.SUCCESS)

    @property
    def t_end_s(self) -> float:
        """t_end (Eq. 4.9) in seconds since the OTS was formed; NaN if not valid."""
        return float(self.trace.t_end) if self.trace is not None else float("nan")

    @property
    def end_state(self) -> np.ndarray:
        """The terminal state s(t_end), or the start state if not valid."""
        return self.trace.final_state if self.trace is not None else self.start_state


#: How the early timeout decides that an object is stuck (`OTSController`'s stall_mode).
STALL_MODES: tuple[str, ...] = ("still", "progress")


class _StallDetector:
    """True once the object made no headway for `period` s.

    'still': the AABB centre (x, y, z) stayed within `tol` of one point. 'progress': the
    centre's x did not get `tol` beyond its best so far in the transfer's direction
    (`sign` +1: towards the TU, -1: towards the TM), whatever it did sideways.
    """

    def __init__(
        self, period: float | None, tol: float, s0: np.ndarray, mode: str = "still",
        sign: float = 1.0,
    ) -> None:  # fmt: skip
        self.period, self.tol = period, tol
        self._progress = mode == "progress"
        self._sign = sign
        self._best = sign * float(s0[Col.X])
        self._anchor = (float(s0[Col.X]), float(s0[Col.Y]), float(s0[Col.Z]))
        self._since = float(s0[Col.T])

    def __call__(self, s: np.ndarray) -> bool:
        v = s.tolist()
        x, t = v[_X], v[_T]
        if self._progress:
            if self._sign * x > self._best + self.tol:
                self._best, self._since = self._sign * x, t
                return False
        else:
            y, z = v[_Y], v[_Z]
            ax, ay, az = self._anchor
            if max(abs(x - ax), abs(y - ay), abs(z - az)) > self.tol:
                self._anchor, self._since = (x, y, z), t
                return False
        return self.period is not None and t - self._since >= self.period - 1e-9


class OTSController:
    """Runs object transfers between a transport module and a transfer unit.

    Args:
        tm, tu: HALs of the transport module and the transfer unit.
        sensor: Object state estimate in F_T.
        clock: Time source.
        thresholds: State-set thresholds (Eq. 5.7–5.9).
        belt_speed_m_s: Surface speed of running belts.
        sample_period_s: Period at which the state is observed and the sets evaluated.
        on_sample: Optional callback run after every observation (e.g. to record frames).
        stall_time_s: Early timeout: a transfer whose object's AABB centre stays within
            `stall_tol_m` of one point for this long ends at once as the timeout it would
            become (t_end = the timeout time); None always waits for t_max.
        stall_tol_m: Displacement below which the object counts as immobile (m).
        stall_mode: 'still' (default): immobile means the AABB centre stays within
            `stall_tol_m` of one point; 'progress': the centre gets no `stall_tol_m`
            further towards the receiving unit (sideways creep at the gap does not count).
    """

    def __init__(
        self,
        tm: UnitHAL,
        tu: UnitHAL,
        sensor: ObjectSensor,
        clock: Clock,
        *,
        thresholds: BeltThresholds,
        belt_speed_m_s: float,
        sample_period_s: float,
        on_sample: Callable[[], None] | None = None,
        stall_time_s: float | None = None,
        stall_tol_m: float = 0.002,
        stall_mode: str = "still",
    ) -> None:
        if stall_mode not in STALL_MODES:
            raise ValueError(f"stall_mode must be one of {STALL_MODES}, got {stall_mode!r}")
        self.tm, self.tu = tm, tu
        self.stall_mode = stall_mode
        self.stall_time_s = stall_time_s
        self.stall_tol_m = stall_tol_m
        self.sensor, self.clock = sensor, clock
        self.thresholds = thresholds
        self.speed = belt_speed_m_s
        self.dt = sample_period_s
        self.on_sample = on_sample

    def state(self, face: str, conveyor: str) -> np.ndarray:
        """The full state vector (Eq. 5.4) now: sensor reading plus f, c and t."""
        s = self._observed(_codes(face, conveyor))
        s[_T] = self.clock.now()
        return s

    def _observed(self, codes: tuple[int, int]) -> np.ndarray:
        """A new state vector with the sensor reading and the codes of f and c (its time
        component left for the caller: the transfer process writes its own clock there)."""
        s = np.empty(N_COLS)
        s[:_F] = self.sensor.observe()
        s[_F], s[_C] = codes
        if self.on_sample is not None:
            self.on_sample()
        return s

    def stop_all(self) -> None:
        """Stop every belt of both units."""
        for hal in (self.tm, self.tu):
            for belt in ("left", "right"):
                hal.set_belt_speed(belt, 0.0)

    def transfer(
        self, direction: TransferDirection, face: str, conveyor: str | None = None
    ) -> TransferRecord:
        """Form the OTS, check the pre-transfer state, run the belts named by c until a
        terminal state (Eq. 4.9) or t_max, stop the belts.

        Like a real unit, the belts stop at once when the receiving unit's far light barrier
        is interrupted, so an object is never driven off the far end.

        Args:
            direction: TM → TU (Eq. 6.16) or TU → TM (Eq. 6.17).
            face: Face f the object lies on.
            conveyor: Conveyor position c; None derives it from the observed AABB's
                overlap with the belts (Eq. 5.6).
        """
        sets = _sets(direction, self.thresholds)
        self.clock.start()
        if conveyor is None:
            obs = np.asarray(self.sensor.observe(), dtype=float)
            code = int(conveyor_of(obs[Col.Y], obs[Col.SY]))
            conveyor = Conveyor(code).name.lower()
        s0 = self.state(face, conveyor)
        if not contains_state(sets.pre, s0):
            return TransferRecord(direction, conveyor, False, s0, None)
        sign = 1.0 if direction is TransferDirection.TM_TO_TU else -1.0
        for hal in (self.tm, self.tu):
            for belt in belts_for(conveyor):
                hal.set_belt_speed(belt, sign * self.speed)

        receiver = self.tu if direction is TransferDirection.TM_TO_TU else self.tm
        stopped = False
        codes = _codes(face, conveyor)
        stall = (
            _StallDetector(self.stall_time_s, self.stall_tol_m, s0, self.stall_mode, sign)
            if self.stall_time_s is not None
            else None
        )
        try:
            # Eq. 4.11 with u = wait one sample period, then observe (the process owns the
            # clock and the termination); no per-sample closure around that work.
            process = TransferProcess(
                s0, pre=sets.pre, success=sets.success, failure=sets.failure, dt=self.dt,
                t_max=self.thresholds.t_max + self.dt, time_index=_T,
            )  # fmt: skip
            while process.running:
                self.clock.wait(self.dt)
                if not stopped and receiver.barriers()["far"]:
                    # Safety stop: the object reached the receiver's far edge.
                    self.stop_all()
                    stopped = True
                process.advance(self._observed(codes))
                if stall is not None and process.running and stall(process.state):
                    process.fast_forward()
            trace = process.trace()
        finally:
            self.stop_all()
        return TransferRecord(direction, conveyor, True, s0, trace)
