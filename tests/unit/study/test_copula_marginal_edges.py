"""The marginals of the docking-error copula (Sec. 6.4) checked against independent numbers
where the mutation run (issue 40) found them open: each candidate's BIC and KS statistic
written out with scipy (BIC = k ln n − 2 ln L at the family's own maximum-likelihood
parameters), the truncated normal's fit against the maximum of its log-likelihood written
out (Φ-normalised normal density), the beta fit on the range's bounds, a record turned down
by the KS gate keeping its figures, the bounds of what can be fitted, and a KDE marginal's
density and exact CDF against scipy's gaussian_kde at its own bandwidth factor.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy import optimize, stats

from transfertwin._errors import InputError
from transfertwin.study.docking._marginals import FAMILIES, RANGE_MARGIN, Marginal, fit_marginal

FAM = {f.name: f for f in FAMILIES}


def _sample(n: int = 60, seed: int = 3) -> np.ndarray:
    return np.random.default_rng(seed).normal(2.0, 1.5, n)


def _bounds(x: np.ndarray) -> tuple[float, float]:
    w = float(np.ptp(x))
    return float(x.min()) - RANGE_MARGIN * w, float(x.max()) + RANGE_MARGIN * w


def test_sec_6_4_normal_candidate_bic_and_ks_written_out() -> None:
    x = _sample()
    fit = fit_marginal(x, "x_mm", families=(FAM["normal"],), ks_alpha=0.01)
    (rec,) = fit.candidates
    mu, sd = float(np.mean(x)), float(np.std(x))
    loglik = float(np.sum(stats.norm.logpdf(x, mu, sd)))
    assert rec.status == "fitted"
    assert rec.bic == pytest.approx(2 * math.log(len(x)) - 2 * loglik, rel=1e-12)
    ks = stats.kstest(x, stats.norm(mu, sd).cdf)
    assert rec.ks_statistic == pytest.approx(ks.statistic, rel=1e-12)
    assert rec.ks_pvalue == pytest.approx(ks.pvalue, rel=1e-12)
    assert fit.ks_alpha == 0.01 and fit.marginal.points == ()
    assert fit.marginal.bounds == pytest.approx(_bounds(x))


def test_sec_6_4_truncnorm_fit_is_the_maximum_of_its_written_out_likelihood() -> None:
    x = _sample(80, 5)
    lo, hi = _bounds(x)

    def nll(p: np.ndarray) -> float:
        mu, s = p[0], math.exp(p[1])
        mass = stats.norm.cdf(hi, mu, s) - stats.norm.cdf(lo, mu, s)
        return -float(np.sum(stats.norm.logpdf(x, mu, s) - math.log(mass)))

    ref = optimize.minimize(nll, [0.0, 0.0], method="Powell", options={"xtol": 1e-10,
                                                                       "ftol": 1e-12})  # fmt: skip
    fit = fit_marginal(x, families=(FAM["truncnorm"],))
    mu, s, f_lo, f_hi = fit.marginal.params
    assert (f_lo, f_hi) == pytest.approx((lo, hi))
    assert mu == pytest.approx(ref.x[0], abs=2e-3)
    assert s == pytest.approx(math.exp(ref.x[1]), rel=2e-3)
    (rec,) = fit.candidates
    assert rec.bic == pytest.approx(4 * math.log(len(x)) + 2 * ref.fun, abs=1e-4)


def test_sec_6_4_beta_is_fitted_on_the_range_bounds() -> None:
    x = np.random.default_rng(2).beta(2.0, 5.0, 200) * 10.0 - 3.0
    lo, hi = _bounds(x)
    fit = fit_marginal(x, families=(FAM["beta"],))
    a, b, loc, scale = fit.marginal.params
    assert (loc, scale) == pytest.approx((lo, hi - lo))
    ref_a, ref_b, _, _ = stats.beta.fit(x, floc=lo, fscale=hi - lo)
    assert (a, b) == pytest.approx((ref_a, ref_b), rel=1e-9)


def test_sec_6_4_a_record_turned_down_by_the_ks_gate_keeps_its_figures() -> None:
    x = np.concatenate([np.full(40, -5.0), np.full(40, 5.0)]) + np.linspace(0, 0.5, 80)
    free = fit_marginal(x, families=(FAM["normal"], FAM["kde"]), ks_alpha=0.0)
    gated = fit_marginal(x, families=(FAM["normal"], FAM["kde"]), ks_alpha=0.05)
    before, after = free.candidates[0], gated.candidates[0]
    assert before.status == "fitted" and after.status == "rejected"
    assert (after.family, after.bic, after.ks_statistic, after.ks_pvalue) == (
        before.family, before.bic, before.ks_statistic, before.ks_pvalue)  # fmt: skip
    assert after.reason == f"KS p = {before.ks_pvalue:.3g} < 0.05"
    assert gated.marginal.family == "kde" and free.marginal.family == "normal"
    assert len(gated.marginal.points) == 80


def test_sec_6_4_two_distinct_values_can_be_fitted() -> None:
    fit = fit_marginal(np.array([0.0, 1.0]), families=(FAM["normal"],), ks_alpha=0.0)
    assert fit.marginal.params == pytest.approx((0.5, 0.5))
    kde = fit_marginal(np.array([0.0, 1.0]), families=(FAM["kde"],))
    assert kde.marginal.points == (0.0, 1.0)


def test_sec_6_4_no_family_fits_lists_every_family() -> None:
    x = np.array([0.0, 0.0, 0.0, 1e-300])  # spread below what a float variance resolves
    with pytest.raises(InputError, match=r"^v: no marginal family fits: normal failed \("
                                         r"ValueError: zero spread\); kde failed"):  # fmt: skip
        fit_marginal(x, "v", families=(FAM["normal"], FAM["kde"]))


def test_sec_6_4_kde_marginal_uses_its_bandwidth_factor_against_scipy() -> None:
    pts = (0.0, 0.4, 1.1, 2.0, 2.2, 3.5)
    m = Marginal("kde", (0.5,), (-1.0, 4.5), pts)
    ref = stats.gaussian_kde(np.array(pts), bw_method=0.5)
    x = np.array([-0.5, 0.7, 2.1, 4.0])
    assert m.dist.logpdf(x) == pytest.approx(ref.logpdf(x), rel=1e-12)
    h = math.sqrt(ref.covariance[0, 0])  # the exact CDF: mean of normal CDFs at the points
    cdf = [float(np.mean(stats.norm.cdf((v - np.array(pts)) / h))) for v in x]
    assert m.dist.cdf(x) == pytest.approx(cdf, rel=1e-12)
    assert m.dist.cdf(np.array([])).shape == (0,)
    assert m.dist.cdf(0.7).shape == () and float(m.dist.cdf(0.7)) == pytest.approx(cdf[1])
    assert m.to_dict()["points"] == list(pts)
    assert "points" not in fit_marginal(_sample(), families=(FAM["normal"],)).marginal.to_dict()


def test_sec_6_4_a_p_value_equal_to_the_level_passes_the_gate() -> None:
    """The gate rejects p < α: at p = α exactly the family stays fitted."""
    x = _sample()
    p = fit_marginal(x, families=(FAM["normal"],), ks_alpha=0.0).candidates[0].ks_pvalue
    at = fit_marginal(x, families=(FAM["normal"],), ks_alpha=p).candidates[0]
    assert at.status == "fitted"
    above = fit_marginal(x, families=(FAM["normal"], FAM["kde"]), ks_alpha=np.nextafter(p, 1))
    assert above.candidates[0].status == "rejected"


def test_sec_6_4_unnamed_values_and_empty_bounds_are_refused_by_name() -> None:
    with pytest.raises(InputError, match=r"^values: needs at least 2 distinct values"):
        fit_marginal(np.array([1.0, 1.0, 1.0]))
    with pytest.raises(InputError, match=r"params and bounds must be finite, lo < hi$"):
        Marginal("normal", (0.0, 1.0), (0.5, 0.5), ())
