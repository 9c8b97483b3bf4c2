"""Clopper–Pearson confidence intervals for a success probability (Sec. 6.7).

The study treats the repeated transfers of one pre-transfer state as Bernoulli
trials and reports p̂ = k/n with an exact (Clopper and Pearson 1934) interval,
i.e. the beta-quantile interval

    low  = Beta⁻¹(α/2; k, n − k + 1)      (0 when k = 0)
    high = Beta⁻¹(1 − α/2; k + 1, n − k)  (1 when k = n)

computed by statsmodels' ``proportion_confint(method="beta")``. A state that was
never run (n = 0) has no interval: both bounds are NaN.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass
from numbers import Integral, Real
from typing import Any

import numpy as np
from statsmodels.stats.proportion import proportion_confint

from transfertwin._errors import InputError

__all__ = ["CLOPPER_PEARSON", "Interval", "clopper_pearson", "clopper_pearson_array"]

#: Value of `Interval.method` for intervals made here.
CLOPPER_PEARSON = "clopper-pearson"


@dataclass(frozen=True)
class Interval:
    """A two-sided confidence interval for a binomial proportion (Sec. 6.7).

    Attributes:
        low: Lower bound in [0, 1]; NaN when n = 0.
        high: Upper bound in [0, 1]; NaN when n = 0.
        method: Name of the interval method, e.g. ``"clopper-pearson"``.
        k: Number of successes.
        n: Number of trials.
        alpha: 1 − confidence level (0.05 for a 95 % interval).
    """

    low: float
    high: float
    method: str = CLOPPER_PEARSON
    k: int = 0
    n: int = 0
    alpha: float = 0.05

    @property
    def p_hat(self) -> float:
        """Point estimate k/n (Eq. 6.26); NaN when n = 0."""
        return self.k / self.n if self.n else math.nan

    @property
    def confidence(self) -> float:
        """Confidence level 1 − α."""
        return 1.0 - self.alpha

    def to_dict(self) -> dict[str, Any]:
        """Plain dict with the dataclass fields; inverse of `from_dict`."""
        return asdict(self)

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> Interval:
        """Rebuild an interval written by `to_dict`."""
        return cls(**data)


def _check_alpha(alpha: float) -> float:
    if isinstance(alpha, bool) or not isinstance(alpha, Real) or not 0.0 < float(alpha) < 1.0:
        raise InputError(f"Clopper-Pearson: alpha must be a number in (0, 1), got {alpha!r}")
    return float(alpha)


def _check_count(value: object, name: str) -> int:
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, Integral) or value < 0:
        raise InputError(f"Clopper-Pearson: {name} must be a non-negative integer, got {value!r}")
    return int(value)


def clopper_pearson(k: int, n: int, alpha: float = 0.05) -> Interval:
    """Exact (Clopper–Pearson) interval for k successes in n trials (Sec. 6.7).

    Args:
        k: Successes, 0 ≤ k ≤ n.
        n: Trials, n ≥ 0; n = 0 gives (NaN, NaN).
        alpha: 1 − confidence level, in (0, 1).

    Returns:
        The interval; ``method == "clopper-pearson"``.

    Raises:
        InputError: On negative or non-integer counts, k > n, or alpha outside (0, 1).
    """
    k, n, alpha = _check_count(k, "k"), _check_count(n, "n"), _check_alpha(alpha)
    if k > n:
        raise InputError(f"Clopper-Pearson: k must not exceed n, got k={k}, n={n}")
    if n == 0:
        return Interval(math.nan, math.nan, CLOPPER_PEARSON, k, n, alpha)
    low, high = proportion_confint(k, n, alpha=alpha, method="beta")
    return Interval(float(low), float(high), CLOPPER_PEARSON, k, n, alpha)


def clopper_pearson_array(
    k: np.ndarray, n: np.ndarray, alpha: float = 0.05
) -> tuple[np.ndarray, np.ndarray]:
    """Vectorised `clopper_pearson` over arrays of equal shape.

    Args:
        k: Successes, integer array of any shape.
        n: Trials, integer array of the same shape; entries with n = 0 give NaN.
        alpha: 1 − confidence level, in (0, 1).

    Returns:
        ``(low, high)``: float arrays of the input shape.

    Raises:
        InputError: On shape mismatch, non-integer or negative counts, or k > n.
    """
    alpha = _check_alpha(alpha)
    k_arr, n_arr = np.asarray(k), np.asarray(n)
    if k_arr.shape != n_arr.shape:
        raise InputError(f"Clopper-Pearson: k {k_arr.shape} and n {n_arr.shape} differ in shape")
    for arr, name in ((k_arr, "k"), (n_arr, "n")):
        if arr.size and (arr.dtype.kind not in "iu" or arr.min() < 0):
            raise InputError(f"Clopper-Pearson: {name} must hold non-negative integers")
    if np.any(k_arr > n_arr):
        raise InputError("Clopper-Pearson: k must not exceed n")
    low = np.full(k_arr.shape, np.nan)
    high = np.full(k_arr.shape, np.nan)
    run = n_arr > 0
    if np.any(run):
        lo, hi = proportion_confint(k_arr[run], n_arr[run], alpha=alpha, method="beta")
        low[run], high[run] = lo, hi
    return low, high
