"""The KDE marginal of the docking-error copula against scipy's own gaussian_kde.

Its CDF must equal `gaussian_kde.integrate_box_1d(-inf, x)` and its inverse-transform
samples (grid-interpolated PPF) must be indistinguishable from `gaussian_kde.resample`.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy import stats

from transfertwin.study.docking._marginals import Marginal


@pytest.fixture(scope="module")
def bimodal() -> np.ndarray:
    rng = np.random.default_rng(3)
    return np.concatenate([rng.normal(-10, 4, 120), rng.normal(7, 3, 80)])


def _kde_marginal(points: np.ndarray) -> tuple[Marginal, stats.gaussian_kde]:
    ref = stats.gaussian_kde(points)
    width = np.ptp(points)
    bounds = (points.min() - 10 * width, points.max() + 10 * width)  # no truncation in effect
    return Marginal("kde", (float(ref.factor),), bounds, tuple(points.tolist())), ref


def test_kde_cdf_equals_scipy_integrate_box_1d(bimodal) -> None:
    marginal, ref = _kde_marginal(bimodal)
    x = np.linspace(-30, 25, 57)
    expected = [ref.integrate_box_1d(-np.inf, v) for v in x]
    np.testing.assert_allclose(marginal.dist.cdf(x), expected, atol=1e-12)


def test_kde_ppf_inverts_the_cdf(bimodal) -> None:
    marginal, ref = _kde_marginal(bimodal)
    q = np.linspace(0.001, 0.999, 99)
    x = marginal.dist.ppf(q)
    np.testing.assert_allclose([ref.integrate_box_1d(-np.inf, v) for v in x], q, atol=1e-4)


def test_kde_inverse_transform_samples_match_scipy_resample(bimodal) -> None:
    marginal, ref = _kde_marginal(bimodal)
    ours = marginal.quantile(np.random.default_rng(5).random(4000))
    theirs = ref.resample(4000, seed=np.random.default_rng(6))[0]
    assert stats.ks_2samp(ours, theirs).pvalue > 0.01
