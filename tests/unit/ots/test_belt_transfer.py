"""Belt OTS end to end: `run_transfer` with a kinematic belt model (Eq. 4.8–4.11, 5.7–5.11).

The model moves the box at belt speed, hands possession over when its centre
passes the middle of the gap and lets a box that is shorter than the gap sink.
"""

from __future__ import annotations

import functools

import numpy as np
import pytest

from transfertwin import InputError
from transfertwin.ots import (
    ASSET_TM,
    ASSET_TU,
    BeltThresholds,
    Col,
    Outcome,
    TransferDirection,
    TransferTrace,
    Transition,
    belt_sets,
    make_states,
    run_transfer,
)

DT = 0.1  # s
TH = BeltThresholds(tu_x_min=0.012, tu_x_max=0.512)  # TU belts behind a 12 mm gap
GAP_MID = 0.006  # m


def belts(
    s: np.ndarray, *, v: float = 0.2, v_y: float = 0.0, tu_running: bool = True
) -> np.ndarray:
    """One time step of belt kinematics (pure); ``v`` in m/s, signed along x."""
    s = s.copy()
    over_gap = s[Col.X] - s[Col.SX] >= 0.0 and s[Col.X] + s[Col.SX] <= TH.tu_x_min
    if over_gap or s[Col.Z] - s[Col.SZ] < 0.0:  # too short to bridge the gap: it falls
        s[Col.Z] -= 0.02
    elif tu_running or s[Col.X] <= GAP_MID:
        s[Col.X] += v * DT
        s[Col.Y] += v_y * DT
    s[Col.A] = ASSET_TU if s[Col.X] > GAP_MID else ASSET_TM
    s[Col.THETA] = np.nan  # not observable during the transfer
    return s


def _s0(**kw: float) -> np.ndarray:
    base = {"a": ASSET_TM, "x": -0.325, "y": 0.0, "z": 0.03, "s_x": 0.1, "s_y": 0.05,
            "s_z": 0.03, "theta": 0.2}  # fmt: skip
    return make_states(**{**base, **kw})[0]


def _run(
    s0: np.ndarray,
    u: Transition,
    direction: TransferDirection = TransferDirection.TM_TO_TU,
) -> TransferTrace:
    sets = belt_sets(direction, TH)
    return run_transfer(
        s0, u, pre=sets.pre, success=sets.success, failure=sets.failure,
        dt=DT, t_max=TH.t_max, time_index=Col.T,
    )  # fmt: skip


def test_eq_5_11_nominal_forward_transfer_succeeds() -> None:
    trace = _run(_s0(), belts)
    assert trace.outcome is Outcome.SUCCESS
    assert trace.final_state[Col.A] == ASSET_TU
    assert trace.final_state[Col.X] > 0.2
    assert trace.t_end == pytest.approx(2.7)  # first x > 0.2 m: -0.325 + 0.02 * 27 = 0.215


def test_eq_5_7_box_over_the_tm_edge_is_rejected() -> None:
    with pytest.raises(InputError, match=r"Eq\. 4\.8"):
        _run(_s0(x=-0.58), belts)


def test_eq_5_9_sideways_drift_off_the_belts_fails() -> None:
    trace = _run(_s0(y=0.1), functools.partial(belts, v_y=0.1))
    assert trace.outcome is Outcome.FAILURE
    assert not trace.timed_out
    assert trace.final_state[Col.Y] + trace.final_state[Col.SY] > 0.2


def test_eq_5_9_short_box_falls_into_the_gap() -> None:
    trace = _run(_s0(x=-0.2, s_x=0.002), functools.partial(belts, v=0.04))
    assert trace.outcome is Outcome.FAILURE
    assert not trace.timed_out
    assert trace.final_state[Col.A] == ASSET_TM
    assert trace.final_state[Col.Z] - trace.final_state[Col.SZ] < -0.03


def test_eq_5_8_stalled_receiver_times_out_at_t_max() -> None:
    trace = _run(_s0(), functools.partial(belts, tu_running=False))
    assert trace.outcome is Outcome.FAILURE
    assert trace.timed_out
    assert trace.t_end == pytest.approx(TH.t_max)


def test_return_transfer_tu_to_tm_succeeds() -> None:
    s0 = _s0(a=ASSET_TU, x=0.3)
    trace = _run(s0, functools.partial(belts, v=-0.2), TransferDirection.TU_TO_TM)
    assert trace.outcome is Outcome.SUCCESS
    assert trace.final_state[Col.A] == ASSET_TM
    assert trace.final_state[Col.X] < -0.2
