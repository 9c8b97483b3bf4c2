"""Scalar `contains_one` against the batched `contains` of the belt sets (Eq. 5.7–5.9) on
states exactly at, and one ulp either side of, every threshold, and with NaN or ±inf in every
column a set reads, for both transfer directions; the scalar `outcome_codes` path
(Eq. 5.11) against the batch one on the same states; and a transfer whose state blows up to
NaN ending as a failure at that step (Eq. 4.9).

The random states of test_fast_paths.py never land on a boundary; these do, since every
threshold and half extent below is a binary fraction, so ``x - s_x`` equals the bound
exactly in float64 in both paths. Where the module docstring fixes the answer at a bound
(inclusive box edges, strict ``t < t_max``, strict success threshold, NaN means failure),
it is asserted as well, so the two paths cannot agree on a wrong answer.
"""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from transfertwin.ots import (
    ASSET_TM,
    ASSET_TU,
    BeltThresholds,
    Col,
    Outcome,
    TransferDirection,
    belt_sets,
    make_states,
    outcome_codes,
    run_transfer,
)
from transfertwin.ots._model import contains_state

# Binary-fraction thresholds: sums and differences below are exact in float64.
TH = BeltThresholds(
    tm_x_min=-0.625, tm_x_max=0.0, tu_x_min=0.0, tu_x_max=0.5, y_min=-0.25, y_max=0.25,
    x_success=0.25, t_max=32.0, z_fall=-0.03125, t0_tol=2.0**-20,
)  # fmt: skip
TH_NO_FALL = BeltThresholds(**{**TH.__dict__, "z_fall": None})
SX, SY, SZ = 0.125, 0.0625, 0.0625
DIRECTIONS = list(TransferDirection)


def _state(**kw: float) -> np.ndarray:
    base = {"a": ASSET_TM, "x": -0.25, "y": 0.0, "z": 0.0625, "s_x": SX, "s_y": SY, "s_z": SZ,
            "theta": 0.0, "f": 0, "c": 0, "t": 0.0}  # fmt: skip
    return make_states(**{**base, **kw})[0]


def _step(centre: float, edge: float | None = None) -> float:
    """The least change of a box centre that moves ``centre ± half extent`` off `edge`."""
    return max(np.spacing(abs(centre)), np.spacing(abs(edge if edge is not None else centre)))


def _past(centre: float, sign: float, edge: float | None = None) -> float:
    """`centre` moved by one least step in the direction of `sign`."""
    return centre + sign * _step(centre, edge)


def _around(centre: float, edge: float | None = None) -> list[float]:
    """`centre` and its nearest values either side that move the box's edge off `edge`."""
    return [_past(centre, -1.0, edge), centre, _past(centre, 1.0, edge)]


def _sx_on_a_bound(th: BeltThresholds) -> list[tuple[float, float]]:
    """(s_x, bound): half extents that put an edge of a base's box (x = -0.25, 0.3125 or
    -0.375 in `_critical_states`) exactly on a bound."""
    return [(0.375, th.tm_x_min), (0.25, th.tm_x_max), (0.1875, th.tu_x_max),
            (0.3125, th.tu_x_min), (0.25, th.tm_x_min)]  # fmt: skip


def _critical_states(th: BeltThresholds) -> np.ndarray:
    """States at and one ulp around every bound of both directions' sets, plus NaN/±inf in
    each read column, from bases on the TM, on the TU and in the gap (N, 11)."""
    x_ret = th.success_threshold(TransferDirection.TU_TO_TM)
    bases = [
        _state(a=ASSET_TM, x=-0.25, t=0.0),  # pre of TM->TU
        _state(a=ASSET_TU, x=0.3125, t=4.0),  # success of TM->TU, pre of TU->TM at t=0
        _state(a=ASSET_TU, x=0.3125, t=0.0),
        _state(a=ASSET_TM, x=-0.375, t=4.0),  # success of TU->TM
        _state(a=ASSET_TM, x=0.0, t=1.0),  # in the gap
    ]
    xs = [(th.tm_x_min + SX, th.tm_x_min), (th.tm_x_max - SX, th.tm_x_max),
          (th.tu_x_min + SX, th.tu_x_min), (th.tu_x_max - SX, th.tu_x_max),
          (th.x_success, None), (x_ret, None)]  # fmt: skip
    values = {
        Col.X: [v for x, edge in xs for v in _around(x, edge)],
        Col.Y: [*_around(th.y_min + SY, th.y_min), *_around(th.y_max - SY, th.y_max)],
        Col.Z: _around(th.z_fall + SZ, th.z_fall) if th.z_fall is not None else [0.0],
        Col.T: [v for t in (th.t0_tol, -th.t0_tol, th.t_max) for v in _around(t)],
        Col.A: [ASSET_TM, ASSET_TU, 0.5, 2.0],
        Col.SX: [v for sx, e in _sx_on_a_bound(th) for v in _around(sx, e)],
        Col.SY: _around(0.25, th.y_max),
        Col.SZ: _around(0.09375, th.z_fall) if th.z_fall is not None else [0.0],
    }
    rows = []
    for base, (col, vals) in itertools.product(bases, values.items()):
        for v in [*vals, np.nan, np.inf, -np.inf]:
            s = base.copy()
            s[col] = v
            rows.append(s)
    for base, col in itertools.product(bases, [Col.THETA, Col.F, Col.C]):  # never read
        s = base.copy()
        s[col] = np.nan
        rows.append(s)
    return np.array(rows)


@pytest.mark.parametrize("th", [TH, TH_NO_FALL], ids=["z_fall", "no_z_fall"])
@pytest.mark.parametrize("direction", DIRECTIONS, ids=lambda d: d.value)
def test_eq_5_7_to_5_9_scalar_path_equals_batch_at_every_bound(
    direction: TransferDirection, th: BeltThresholds
) -> None:
    states = _critical_states(th)
    sets = belt_sets(direction, th)
    for name in ("pre", "success", "failure"):
        s = getattr(sets, name)
        batch = s.contains(states)
        scalar = np.array([s.contains_one(x) for x in states])
        bad = np.flatnonzero(batch != scalar)
        assert bad.size == 0, f"{direction.value} {name}: scalar differs on {states[bad[:3]]}"
        assert 0 < batch.sum() < len(states), f"{name}: the states must straddle the set"
        assert all(contains_state(s, x) is bool(b) for x, b in zip(states, batch, strict=True))
    codes = outcome_codes(states, sets.success, sets.failure)
    one = [int(outcome_codes(x, sets.success, sets.failure)) for x in states]
    assert (codes == one).all()
    assert set(codes.tolist()) == {-1, 0, 1}


def _both(s: object, x: np.ndarray) -> bool:
    """Membership by both paths, which must agree."""
    batch, scalar = bool(s.contains(x)), s.contains_one(x)  # type: ignore[attr-defined]
    assert batch is scalar, f"contains {batch} but contains_one {scalar}"
    return batch


@pytest.mark.parametrize("direction", DIRECTIONS, ids=lambda d: d.value)
def test_eq_5_7_pre_box_edges_inclusive_time_within_tolerance(direction) -> None:
    pre = belt_sets(direction, TH).pre
    fwd = direction is TransferDirection.TM_TO_TU
    lo, hi = (TH.tm_x_min, TH.tm_x_max) if fwd else (TH.tu_x_min, TH.tu_x_max)
    a, other = (ASSET_TM, ASSET_TU) if fwd else (ASSET_TU, ASSET_TM)
    assert _both(pre, _state(a=a, x=lo + SX))
    assert not _both(pre, _state(a=a, x=_past(lo + SX, -1, lo)))
    assert _both(pre, _state(a=a, x=hi - SX))
    assert not _both(pre, _state(a=a, x=_past(hi - SX, 1, hi)))
    mid = (lo + hi) / 2
    assert _both(pre, _state(a=a, x=mid, y=TH.y_max - SY))
    assert not _both(pre, _state(a=a, x=mid, y=_past(TH.y_max - SY, 1, TH.y_max)))
    assert _both(pre, _state(a=a, x=mid, y=TH.y_min + SY))
    assert not _both(pre, _state(a=a, x=mid, y=_past(TH.y_min + SY, -1, TH.y_min)))
    assert _both(pre, _state(a=a, x=mid, t=TH.t0_tol))
    assert _both(pre, _state(a=a, x=mid, t=-TH.t0_tol))
    assert not _both(pre, _state(a=a, x=mid, t=np.nextafter(TH.t0_tol, 1)))
    assert not _both(pre, _state(a=a, x=mid, t=np.nextafter(-TH.t0_tol, -1)))
    assert not _both(pre, _state(a=other, x=mid))
    for col in (Col.A, Col.X, Col.Y, Col.SX, Col.SY, Col.T):
        s = _state(a=a, x=mid)
        s[col] = np.nan
        assert not _both(pre, s), f"NaN in {col.name} must not be pre-transfer"


@pytest.mark.parametrize("direction", DIRECTIONS, ids=lambda d: d.value)
def test_eq_5_8_success_threshold_strict_time_strict(direction) -> None:
    success = belt_sets(direction, TH).success
    fwd = direction is TransferDirection.TM_TO_TU
    thr = TH.success_threshold(direction)
    a = ASSET_TU if fwd else ASSET_TM
    inward = 1.0 if fwd else -1.0  # the side of the threshold that is success
    assert not _both(success, _state(a=a, x=thr, t=4.0))
    assert _both(success, _state(a=a, x=np.nextafter(thr, inward), t=4.0))
    x_in = thr + inward * 0.0625
    assert _both(success, _state(a=a, x=x_in, t=np.nextafter(TH.t_max, 0)))
    assert not _both(success, _state(a=a, x=x_in, t=TH.t_max))
    far = TH.tu_x_max if fwd else TH.tm_x_min  # the receiver's far end
    edge = far - inward * SX
    assert _both(success, _state(a=a, x=edge, t=4.0))
    assert not _both(success, _state(a=a, x=_past(edge, inward, far), t=4.0))
    y_hi, y_lo = TH.y_max - SY, TH.y_min + SY
    assert _both(success, _state(a=a, x=x_in, y=y_hi, t=4.0))
    assert not _both(success, _state(a=a, x=x_in, y=_past(y_hi, 1, TH.y_max), t=4.0))
    assert _both(success, _state(a=a, x=x_in, y=y_lo, t=4.0))
    assert not _both(success, _state(a=a, x=x_in, y=_past(y_lo, -1, TH.y_min), t=4.0))
    for col in (Col.A, Col.X, Col.Y, Col.SX, Col.SY, Col.T):
        s = _state(a=a, x=x_in, t=4.0)
        s[col] = np.nan
        assert not _both(success, s), f"NaN in {col.name} must not be success"


@pytest.mark.parametrize("th", [TH, TH_NO_FALL], ids=["z_fall", "no_z_fall"])
def test_eq_5_9_failure_edges_strict_nan_and_inf_fail(th: BeltThresholds) -> None:
    failure = belt_sets(TransferDirection.TM_TO_TU, th).failure
    inside = _state(a=ASSET_TU, x=0.25, t=4.0)
    assert not _both(failure, inside)
    for col, bound, out, edge in [
        (Col.X, th.tm_x_min + SX, -1.0, th.tm_x_min), (Col.X, th.tu_x_max - SX, 1.0, th.tu_x_max),
        (Col.Y, th.y_min + SY, -1.0, th.y_min), (Col.Y, th.y_max - SY, 1.0, th.y_max),
        (Col.T, th.t_max, 1.0, None),
    ]:  # fmt: skip
        at = inside.copy()
        at[col] = bound
        assert not _both(failure, at), f"{col.name} at its bound is not yet failure"
        at[col] = _past(bound, out, edge)
        assert _both(failure, at), f"{col.name} one ulp beyond its bound is failure"
    for col in (Col.X, Col.Y, Col.SX, Col.SY, Col.T):
        for v in (np.nan, np.inf, -np.inf):
            s = inside.copy()
            s[col] = v
            assert _both(failure, s), f"{v} in {col.name} is failure"
    for col in (Col.Z, Col.SZ):  # read only with the fall extension
        for v in (np.nan, np.inf, -np.inf):
            s = inside.copy()
            s[col] = v
            fails = th.z_fall is not None
            assert _both(failure, s) is fails, f"{v} in {col.name}, z_fall={th.z_fall}"
    if th.z_fall is not None:
        at = _state(a=ASSET_TU, x=0.25, t=4.0, z=th.z_fall + SZ)
        assert not _both(failure, at)  # bottom exactly at z_fall: not yet fallen
        at[Col.Z] = _past(th.z_fall + SZ, -1, th.z_fall)
        assert _both(failure, at)


@pytest.mark.parametrize("direction", DIRECTIONS, ids=lambda d: d.value)
def test_eq_4_9_a_state_that_blows_up_to_nan_ends_the_transfer_at_that_step(direction) -> None:
    sets = belt_sets(direction, TH)
    fwd = direction is TransferDirection.TM_TO_TU
    s0 = _state(a=ASSET_TM if fwd else ASSET_TU, x=-0.25 if fwd else 0.25)
    steps = []

    def u(s: np.ndarray) -> np.ndarray:
        steps.append(1)
        if len(steps) == 3:
            s[Col.Y] = np.nan  # a simulation that blew up
        return s

    trace = run_transfer(s0, u, pre=sets.pre, success=sets.success, failure=sets.failure,
                         dt=0.25, t_max=TH.t_max, time_index=int(Col.T))  # fmt: skip
    assert trace.outcome is Outcome.FAILURE and not trace.timed_out
    assert trace.n_transitions == 3 and len(steps) == 3
    assert trace.t_end == 0.75
