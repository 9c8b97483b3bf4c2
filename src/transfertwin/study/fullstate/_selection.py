"""Smoothing over the yaw circle and best/worst state selection (Eq. 6.27, Alg. 1–4).

A series (Eq. 6.21–6.25) maps yaw angles θ ∈ -179..180° to values; it is
circular, so -179° and 180° are neighbours. A *window of half size h* centred at
θ_i holds the series entries whose circular distance to θ_i is at most h degrees;
for h ≥ 180 it holds the whole circle.

Decisions the study leaves open (see also docs/design-choices.md, "Analysis and selection"):

* **Exact arithmetic.** Values are held as `fractions.Fraction` (floats convert
  exactly), window sums are integer sums over a common denominator, so equal
  window means compare equal whatever the summation order; floats appear only
  in outputs.
* **Missing θ.** A series may lack angles (a coarse θ step, states never run).
  Every window mean — the moving average of Eq. 6.27 and the widening windows of
  Alg. 1/4 — is the mean of the entries present in the window. On a full
  360-entry series this is exactly the study's ``1/(2h+1) Σ`` form.
* **Applied half window** (output of Alg. 1/4): 0 when a single extreme exists
  from the start; otherwise the h at which a single candidate first remained;
  180 when candidates are still tied once the window covers the whole circle,
  in which case the lowest θ is taken. The printed pseudo-code increments its
  counter after the last pass and so returns this value + 1; the offset is
  the same for every series, so Alg. 2/3 choose the same state.
* **Alg. 2 slip.** The printed Alg. 2 never updates MaxValueGlobal and compares
  a value with a state in its tie test. Implemented intent: highest ȳ^MA; ties →
  larger applied half window; remaining ties → the earlier series in the given
  order (front-left, front-right, back-left, back-right in the study).
* **Alg. 3 slip.** The printed Alg. 3 has the same two slips and replaces a tied
  candidate only if its half window is *smaller* than MinHalfWindowSize, which
  starts at 0, so the test never fires. Implemented intent, mirroring Alg. 2:
  lowest ȳ^MA; ties → larger applied half window (the wider, more certain low
  region); remaining ties → series order.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from fractions import Fraction
from numbers import Integral, Real

import numpy as np

from transfertwin._errors import InputError
from transfertwin.ots import THETA_ALL, check_theta_deg

__all__ = [
    "FULL_CIRCLE_HALF_WINDOW",
    "CircularSeries",
    "GlobalChoice",
    "LocalChoice",
    "best_global",
    "best_local",
    "circular_moving_average",
    "moving_average",
    "worst_global",
    "worst_local",
]

_N = 360
#: Half window (degrees) from which a window covers the whole yaw circle.
FULL_CIRCLE_HALF_WINDOW = 180


def _as_fraction(value: object) -> Fraction:
    if isinstance(value, Fraction):
        return value
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, Real):
        raise InputError(f"series values must be finite numbers, got {value!r} (Eq. 6.27)")
    if isinstance(value, Integral):
        return Fraction(int(value))
    if not math.isfinite(float(value)):
        raise InputError(f"series values must be finite numbers, got {value!r} (Eq. 6.27)")
    return Fraction(float(value))


@dataclass(frozen=True)
class CircularSeries:
    """Values over the yaw circle (Eq. 6.25–6.28), θ strictly ascending.

    Attributes:
        theta_deg: Yaw angles present, integers in -179..180, strictly ascending.
        values: One exact value per angle (ȳ or ȳ^MA); numbers are converted
            to `Fraction` exactly.
    """

    theta_deg: tuple[int, ...]
    values: tuple[Fraction, ...]

    def __post_init__(self) -> None:
        theta = tuple(check_theta_deg(t) for t in self.theta_deg)
        values = tuple(_as_fraction(v) for v in self.values)
        if not theta:
            raise InputError("a series needs at least one angle (Eq. 6.25)")
        if len(theta) != len(values):
            raise InputError(f"{len(theta)} angles but {len(values)} values (Eq. 6.25)")
        if any(b <= a for a, b in itertools.pairwise(theta)):
            raise InputError("series angles must be strictly ascending (Eq. 6.25)")
        object.__setattr__(self, "theta_deg", theta)
        object.__setattr__(self, "values", values)

    def as_array(self) -> np.ndarray:
        """Float values ``(len(theta_deg),)``."""
        return np.array([float(v) for v in self.values])


class _WindowSums:
    """O(1) exact window means over a `CircularSeries` via circular prefix sums."""

    def __init__(self, series: CircularSeries) -> None:
        denom = math.lcm(*(v.denominator for v in series.values))
        nums = [0] * _N
        has = [0] * _N
        for theta, v in zip(series.theta_deg, series.values, strict=True):
            nums[theta + 179] = v.numerator * (denom // v.denominator)
            has[theta + 179] = 1
        self._denom = denom
        self._sum = list(itertools.accumulate(nums, initial=0))
        self._cnt = list(itertools.accumulate(has, initial=0))

    def _range(self, prefix: list[int], lo: int, hi: int) -> int:
        # Sum over positions lo..hi (inclusive), indices taken modulo 360.
        if lo < 0:
            return prefix[_N] - prefix[lo + _N] + prefix[hi + 1]
        if hi >= _N:
            return prefix[_N] - prefix[lo] + prefix[hi - _N + 1]
        return prefix[hi + 1] - prefix[lo]

    def mean(self, theta_deg: int, half: int) -> Fraction:
        """Mean of the entries within ``half`` degrees of ``theta_deg``."""
        if half >= FULL_CIRCLE_HALF_WINDOW:
            total, count = self._sum[_N], self._cnt[_N]
        else:
            p = theta_deg + 179
            total = self._range(self._sum, p - half, p + half)
            count = self._range(self._cnt, p - half, p + half)
        return Fraction(total, count * self._denom)


def _check_window(window: int) -> int:
    ok = isinstance(window, Integral) and not isinstance(window, bool)
    if not ok or window < 1 or window % 2 == 0 or window > 2 * FULL_CIRCLE_HALF_WINDOW + 1:
        raise InputError(f"window must be an odd integer in 1..361, got {window!r} (Eq. 6.27)")
    return int(window)


def moving_average(series: CircularSeries, window: int = 21) -> CircularSeries:
    """Centred circular moving average ȳ^MA (Eq. 6.27), exact.

    Args:
        series: Mean results ȳ (Eq. 6.26) over the angles present.
        window: Odd window length in degrees (21 in the study: θ ± 10°).

    Returns:
        A series on the same angles; each value is the mean of the present
        entries within ``(window − 1) / 2`` degrees, wrapping around ±180°.
    """
    half = (_check_window(window) - 1) // 2
    sums = _WindowSums(series)
    return CircularSeries(series.theta_deg, tuple(sums.mean(t, half) for t in series.theta_deg))


def circular_moving_average(values: Sequence[float] | np.ndarray, window: int = 21) -> np.ndarray:
    """Float form of Eq. 6.27 over the full circle.

    Args:
        values: ``(360,)`` values aligned with θ = -179..180; NaN marks a missing angle.
        window: Odd window length in degrees.

    Returns:
        ``(360,)`` float array, NaN where the input is NaN.
    """
    arr = np.asarray(values, dtype=float)
    if arr.shape != (_N,):
        raise InputError(f"expected 360 values for θ = -179..180, got {arr.shape} (Eq. 6.27)")
    present = ~np.isnan(arr)
    if not present.any():
        return arr.copy()
    thetas = tuple(t for t, ok in zip(THETA_ALL, present, strict=True) if ok)
    smoothed = moving_average(CircularSeries(thetas, tuple(arr[present].tolist())), window)
    out = np.full(_N, np.nan)
    out[present] = smoothed.as_array()
    return out


@dataclass(frozen=True)
class LocalChoice:
    """Result of Alg. 1 (best) or Alg. 4 (worst) on one series.

    Attributes:
        index: Position of the chosen entry in the series.
        theta_deg: Its yaw angle, degrees.
        value: Its exact ȳ^MA.
        half_window: Applied half window in degrees (module docstring).
    """

    index: int
    theta_deg: int
    value: Fraction
    half_window: int


def _local(series: CircularSeries, pick: Callable[..., Fraction]) -> LocalChoice:
    extreme = pick(series.values)
    cands = [i for i, v in enumerate(series.values) if v == extreme]
    sums = _WindowSums(series)
    half = 0
    while len(cands) > 1:
        half += 1
        if half >= FULL_CIRCLE_HALF_WINDOW:
            cands = cands[:1]  # whole circle covered: lowest θ (angles ascend)
            break
        means = [sums.mean(series.theta_deg[i], half) for i in cands]
        target = pick(means)
        cands = [i for i, m in zip(cands, means, strict=True) if m == target]
    i = cands[0]
    return LocalChoice(i, series.theta_deg[i], series.values[i], half)


def best_local(series: CircularSeries) -> LocalChoice:
    """Alg. 1: best state of one smoothed series.

    Keeps the entries with maximal ȳ^MA, then widens a centred window
    (h = 1, 2, …) over the smoothed series and keeps those with the maximal
    window mean until one remains; ties at h = 180 go to the lowest θ.
    """
    return _local(series, max)


def worst_local(series: CircularSeries) -> LocalChoice:
    """Alg. 4: worst state of one smoothed series (Alg. 1 with min for max)."""
    return _local(series, min)


@dataclass(frozen=True)
class GlobalChoice:
    """Result of Alg. 2 (best) or Alg. 3 (worst) over several series.

    Attributes:
        series_index: Position of the winning series in the input sequence.
        local: The winning series' local choice.
    """

    series_index: int
    local: LocalChoice


def _global(
    series: Sequence[CircularSeries], local: Callable[[CircularSeries], LocalChoice], sign: int
) -> GlobalChoice:
    if not series:
        raise InputError("at least one series is needed (Alg. 2/3)")
    winner: GlobalChoice | None = None
    for idx, s in enumerate(series):
        cand = local(s)
        if winner is None:
            winner = GlobalChoice(idx, cand)
            continue
        diff = sign * (cand.value - winner.local.value)
        if diff > 0 or (diff == 0 and cand.half_window > winner.local.half_window):
            winner = GlobalChoice(idx, cand)
    return winner


def best_global(series: Sequence[CircularSeries]) -> GlobalChoice:
    """Alg. 2: best state over smoothed series given in priority order.

    Highest ȳ^MA wins; ties go to the larger applied half window, then to the
    earlier series. See the module docstring for the printed pseudo-code's slip.
    """
    return _global(series, best_local, +1)


def worst_global(series: Sequence[CircularSeries]) -> GlobalChoice:
    """Alg. 3: worst state over smoothed series given in priority order.

    Lowest ȳ^MA wins; ties go to the larger applied half window, then to the
    earlier series. See the module docstring for the printed pseudo-code's slips.
    """
    return _global(series, worst_local, -1)
