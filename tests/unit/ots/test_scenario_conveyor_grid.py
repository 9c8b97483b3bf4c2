"""Sec. 4.2, example (a): one module hop on a decentralised conveyor grid.

State (a, p, rfid_src, rfid_tgt, barrier_src, barrier_tgt): possessing module
(0 source, 1 target), object centre p in metres along the hop axis (source module
spans [-0.5, 0], target [0, 0.5]), whether each module's RFID reader reads the
object's tag, and whether any outer-edge light barrier of each module is
interrupted. Steps are multiples of 1/16 m, so positions are exact floats.
"""

from __future__ import annotations

import functools

import numpy as np
import pytest

from transfertwin import InputError
from transfertwin.ots import IntersectionSet, Outcome, PossessionSet, PredicateSet, run_transfer

SOURCE, TARGET = 0.0, 1.0
A, P, RFID_SRC, RFID_TGT, BAR_SRC, BAR_TGT = range(6)
HALF_LEN = 0.1  # object half length, m
MODULES = {SOURCE: (-0.5, 0.0), TARGET: (0.0, 0.5)}  # module extents, m
RFID_RANGE = 0.0625  # reader range around the module centre, m
STEP = 0.0625  # conveyor travel per transition, m


def sense(a: float, p: float) -> np.ndarray:
    """State with the sensor readings of an object at p (pure)."""
    out = [a, p]
    for lo, hi in MODULES.values():
        out.append(float(abs(p - (lo + hi) / 2) <= RFID_RANGE))
    for lo, hi in MODULES.values():
        out.append(float(any(p - HALF_LEN < edge < p + HALF_LEN for edge in (lo, hi))))
    return np.array(out)


def hop(s: np.ndarray, *, target_drive_ok: bool = True) -> np.ndarray:
    """Both module drives run; possession follows the object's centre."""
    p = s[P]
    if p <= 0.0 or target_drive_ok:
        p += STEP
    return sense(TARGET if p > 0.0 else SOURCE, p)


def _pre(s: np.ndarray) -> np.ndarray:
    return (s[:, RFID_SRC] == 1) & (s[:, BAR_SRC] == 0) & (s[:, BAR_TGT] == 0)


def _success(s: np.ndarray) -> np.ndarray:
    return (s[:, RFID_TGT] == 1) & (s[:, BAR_TGT] == 0)


def _off_grid(s: np.ndarray) -> np.ndarray:
    return (s[:, P] > MODULES[TARGET][1]) | (s[:, P] < MODULES[SOURCE][0])


SETS = {
    "pre": IntersectionSet(PossessionSet(SOURCE), PredicateSet(_pre, "grid pre")),  # Eq. 4.4
    "success": IntersectionSet(PossessionSet(TARGET), PredicateSet(_success)),  # Eq. 4.5
    "failure": PredicateSet(_off_grid, "grid s-"),  # Eq. 4.6
}


def test_eq_4_8_nominal_hop_succeeds_with_possession_change() -> None:
    trace = run_transfer(sense(SOURCE, -0.25), hop, dt=0.1, t_max=5.0, **SETS)
    assert trace.outcome is Outcome.SUCCESS
    assert trace.final_state[P] == pytest.approx(0.1875)
    assert trace.states[0, A] == SOURCE and trace.final_state[A] == TARGET
    # the target's barriers were interrupted on the way, then cleared (Eq. 4.9)
    assert np.any(trace.states[:, BAR_TGT] == 1)
    assert trace.final_state[BAR_TGT] == 0 and trace.final_state[RFID_TGT] == 1


def test_eq_4_4_object_overhanging_the_source_edge_is_not_pre_transfer() -> None:
    s0 = sense(SOURCE, -0.4375)
    assert s0[BAR_SRC] == 1
    with pytest.raises(InputError, match=r"Eq\. 4\.8"):
        run_transfer(s0, hop, dt=0.1, t_max=5.0, **SETS)


def test_eq_4_9_stalled_target_drive_times_out_as_failure() -> None:
    stalled = functools.partial(hop, target_drive_ok=False)
    trace = run_transfer(sense(SOURCE, -0.25), stalled, dt=0.1, t_max=5.0, **SETS)
    assert trace.outcome is Outcome.FAILURE
    assert trace.timed_out
    assert trace.final_state[BAR_TGT] == 1  # stuck across the module edge


def test_eq_4_6_broken_target_reader_runs_object_off_the_grid() -> None:
    def blind_hop(s: np.ndarray) -> np.ndarray:
        out = hop(s)
        out[RFID_TGT] = 0.0
        return out

    trace = run_transfer(sense(SOURCE, -0.25), blind_hop, dt=0.1, t_max=5.0, **SETS)
    assert trace.outcome is Outcome.FAILURE
    assert not trace.timed_out
    assert trace.final_state[P] > 0.5
