"""The controller's early timeout: 'still' and 'progress' stall modes on scripted motion.

A scripted object (no physics): it rides the belts towards the TU at belt speed, gets stuck
at the gap at x = 17 mm and creeps sideways at 2 mm/s (what a core does on the prism-pulley
scene); optionally it passes after a while. The sensor reads the script at the clock's time.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from transfertwin.control import OTSController
from transfertwin.ots import BeltThresholds, TransferDirection

SPEED = 0.15
X0, Y0, X_STUCK = -0.325, 0.094, 0.017


class _Clock:
    def __init__(self) -> None:
        self.t, self.t0 = 0.0, 0.0

    def now(self) -> float:
        return self.t - self.t0

    def start(self) -> None:
        self.t0 = self.t

    def wait(self, dt_s: float) -> None:
        self.t += dt_s


class _HAL:
    def __init__(self) -> None:
        self.speeds = {"left": 0.0, "right": 0.0}

    def set_belt_speed(self, belt: str, speed_m_s: float) -> None:
        self.speeds[belt] = speed_m_s

    def belt_speed(self, belt: str) -> float:
        return self.speeds[belt]

    def barriers(self) -> dict[str, bool]:
        return {"near": False, "far": False}


class _Script:
    """x, y of a core that reaches the gap, creeps sideways, and passes at `pass_at` s."""

    def __init__(self, clock: _Clock, pass_at: float = math.inf, sign: float = 1.0) -> None:
        self.clock, self.pass_at, self.sign = clock, pass_at, sign

    def observe(self) -> np.ndarray:
        t = self.clock.t
        t_gap = (X_STUCK - X0) / SPEED
        if t < t_gap:
            x, y = X0 + SPEED * t, Y0
        elif t < self.pass_at:
            x, y = X_STUCK, Y0 - 0.002 * (t - t_gap)  # stuck in x, creeping sideways
        else:
            x, y = X_STUCK + SPEED * (t - self.pass_at), Y0 - 0.002 * (self.pass_at - t_gap)
        a = 1.0 if x > 0.006 else 0.0
        return np.array([a, self.sign * x, y, 0.04, 0.05, 0.045, 0.04, 0.0])


def _transfer(mode: str | None, pass_at: float = math.inf):
    clock = _Clock()
    ctl = OTSController(_HAL(), _HAL(), _Script(clock, pass_at), clock,
                        thresholds=BeltThresholds(t_max=30.0), belt_speed_m_s=SPEED,
                        sample_period_s=0.065, stall_time_s=None if mode is None else 5.0,
                        stall_mode=mode or "still")  # fmt: skip
    return ctl.transfer(TransferDirection.TM_TO_TU, "front", "left"), clock


def test_sideways_creep_is_not_still_so_the_transfer_runs_to_t_max():
    record, clock = _transfer("still")
    assert record.y == 0
    assert 30.0 < record.t_end_s <= 30.0 + 2 * 0.065  # the last sample after t_max
    assert clock.t > 29.9  # simulated to the end


def test_progress_mode_ends_a_creeping_transfer_five_seconds_after_it_stopped_advancing():
    record, clock = _transfer("progress")
    t_gap = (X_STUCK - X0) / SPEED
    assert record.y == 0
    assert record.t_end_s == _transfer("still")[0].t_end_s  # recorded as the timeout
    assert t_gap + 5.0 <= clock.t < t_gap + 5.2  # but simulated only until then


def test_progress_mode_gives_up_a_late_pass_that_still_mode_keeps():
    # The documented cost of the opt-in mode: a core that creeps for 10 s, then passes.
    late = 2.1 + 10.0
    assert _transfer("still", late)[0].y == 1
    assert _transfer(None, late)[0].y == 1
    assert _transfer("progress", late)[0].y == 0


class _Receding:
    """An object on the TU (x = 0.3 m) drifting away from the TM at 4 mm/s."""

    def __init__(self, clock: _Clock) -> None:
        self.clock = clock

    def observe(self) -> np.ndarray:
        return np.array([1.0, 0.3 + 0.004 * self.clock.t, 0.0, 0.04, 0.05, 0.045, 0.04, 0.0])


@pytest.mark.parametrize(("mode", "runs_s"), [("still", 30.0), ("progress", 5.0)])
def test_progress_counts_only_advance_towards_the_receiver(mode: str, runs_s: float):
    # Return transfer: moving away from the TM is motion ('still' goes on) but no
    # progress ('progress' ends it 5 s after the start).
    clock = _Clock()
    ctl = OTSController(_HAL(), _HAL(), _Receding(clock), clock,
                        thresholds=BeltThresholds(t_max=30.0), belt_speed_m_s=SPEED,
                        sample_period_s=0.065, stall_time_s=5.0, stall_mode=mode)  # fmt: skip
    record = ctl.transfer(TransferDirection.TU_TO_TM, "front", "both")
    assert record.valid and record.y == 0
    assert clock.t == pytest.approx(runs_s, abs=0.07)


def test_unknown_stall_mode_is_refused():
    clock = _Clock()
    with pytest.raises(ValueError, match="stall_mode"):
        OTSController(_HAL(), _HAL(), _Script(clock), clock, thresholds=BeltThresholds(),
                      belt_speed_m_s=SPEED, sample_period_s=0.065, stall_mode="fast")  # fmt: skip
