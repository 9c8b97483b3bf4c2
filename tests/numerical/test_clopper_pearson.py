"""Clopper–Pearson intervals (Sec. 6.7) against independent reference values.

Published values, four decimals, of the exact binomial interval: 0/10 →
[0, 0.3085] and 100/200 → [0.4287, 0.5713].
Closed forms: for k = 0 the upper bound is 1 − (α/2)^(1/n); for k = n the lower
bound is (α/2)^(1/n). Defining property (checked with scipy's binomial CDF, not
the beta quantile statsmodels uses): P(X ≥ k | p = low) = α/2 and
P(X ≤ k | p = high) = α/2.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.stats import binom

from transfertwin._errors import InputError
from transfertwin.study.fullstate._intervals import Interval, clopper_pearson, clopper_pearson_array


@pytest.mark.parametrize(
    ("k", "n", "low", "high"),
    [(0, 10, 0.0, 0.3085), (100, 200, 0.4287, 0.5713)],
)
def test_sec_6_7_clopper_pearson_published_values(k: int, n: int, low: float, high: float) -> None:
    ci = clopper_pearson(k, n)
    assert ci.low == pytest.approx(low, abs=5e-5)
    assert ci.high == pytest.approx(high, abs=5e-5)
    assert ci.method == "clopper-pearson"
    assert ci.p_hat == k / n


@pytest.mark.parametrize("n", [1, 10, 20, 50])
def test_sec_6_7_clopper_pearson_closed_forms_at_the_edges(n: int) -> None:
    assert clopper_pearson(0, n).high == pytest.approx(1 - 0.025 ** (1 / n), rel=1e-10)
    assert clopper_pearson(0, n).low == 0.0
    assert clopper_pearson(n, n).low == pytest.approx(0.025 ** (1 / n), rel=1e-10)
    assert clopper_pearson(n, n).high == 1.0


@pytest.mark.parametrize(("k", "n"), [(1, 20), (7, 20), (26, 50), (49, 50)])
def test_sec_6_7_clopper_pearson_tail_probabilities(k: int, n: int) -> None:
    ci = clopper_pearson(k, n, alpha=0.05)
    assert binom.sf(k - 1, n, ci.low) == pytest.approx(0.025, rel=1e-7)
    assert binom.cdf(k, n, ci.high) == pytest.approx(0.025, rel=1e-7)


def test_sec_6_7_no_trials_has_no_interval() -> None:
    ci = clopper_pearson(0, 0)
    assert math.isnan(ci.low) and math.isnan(ci.high) and math.isnan(ci.p_hat)


def test_sec_6_7_vectorised_matches_scalar_and_handles_n_zero() -> None:
    k, n = np.array([[0, 3], [5, 0]]), np.array([[10, 10], [5, 0]])
    low, high = clopper_pearson_array(k, n)
    assert low.shape == high.shape == (2, 2)
    for idx in [(0, 0), (0, 1), (1, 0)]:
        ci = clopper_pearson(int(k[idx]), int(n[idx]))
        assert (low[idx], high[idx]) == pytest.approx((ci.low, ci.high), abs=1e-15)
    assert np.isnan(low[1, 1]) and np.isnan(high[1, 1])


def test_sec_6_7_interval_round_trips_to_dict() -> None:
    ci = clopper_pearson(3, 12, alpha=0.1)
    assert Interval.from_dict(ci.to_dict()) == ci
    assert ci.confidence == pytest.approx(0.9)


@pytest.mark.parametrize(
    ("k", "n", "alpha"), [(5, 4, 0.05), (-1, 4, 0.05), (1.5, 4, 0.05), (1, 4, 0.0), (True, 4, 0.05)]
)
def test_sec_6_7_bad_counts_raise_input_error(k: object, n: object, alpha: float) -> None:
    with pytest.raises(InputError, match="Clopper-Pearson"):
        clopper_pearson(k, n, alpha)  # type: ignore[arg-type]


def test_sec_6_7_vectorised_rejects_bad_arrays() -> None:
    with pytest.raises(InputError):
        clopper_pearson_array(np.array([3]), np.array([2]))
    with pytest.raises(InputError):
        clopper_pearson_array(np.array([1, 2]), np.array([2]))
    with pytest.raises(InputError):
        clopper_pearson_array(np.array([0.5]), np.array([2]))
