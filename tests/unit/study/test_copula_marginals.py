"""Marginals F_i of the docking-error copula (Sec. 6.4): criterion, failures, bounds, dicts."""

from __future__ import annotations

import json

import numpy as np
import pytest
from scipy import stats

from transfertwin._errors import InputError
from transfertwin.study.docking._marginals import (
    FAMILIES,
    Marginal,
    MarginalFamily,
    MarginalFit,
    fit_marginal,
)


def _raise(x: np.ndarray, b: tuple[float, float]) -> tuple[float, ...]:
    raise RuntimeError("optimiser diverged")


BROKEN = MarginalFamily("broken", ("p",), 1, _raise, lambda p, _: stats.norm())
NAN = MarginalFamily("nan", ("p",), 1, lambda x, b: (float("nan"),), lambda p, _: stats.norm())
NORMAL = next(f for f in FAMILIES if f.name == "normal")
KDE = next(f for f in FAMILIES if f.name == "kde")


def test_sec_6_4_failed_family_is_recorded_with_its_reason_and_skipped() -> None:
    x = np.random.default_rng(0).normal(1.0, 2.0, 150)
    fit = fit_marginal(x, "x", families=(BROKEN, NAN, NORMAL))
    by_name = {c.family: c for c in fit.candidates}
    assert by_name["broken"].status == "failed"
    assert "RuntimeError: optimiser diverged" in by_name["broken"].reason
    assert by_name["nan"].status == "failed" and "non-finite" in by_name["nan"].reason
    assert fit.marginal.family == "normal"


def test_sec_6_4_no_family_left_is_one_line_input_error() -> None:
    x = np.random.default_rng(0).normal(size=50)
    with pytest.raises(InputError, match="dock_err_x_mm: no marginal family fits") as info:
        fit_marginal(x, "dock_err_x_mm", families=(BROKEN, NAN))
    assert "optimiser diverged" in str(info.value) and "\n" not in str(info.value)


def test_sec_6_4_ks_gate_rejects_unimodal_families_for_bimodal_data() -> None:
    rng = np.random.default_rng(2)
    x = np.concatenate([rng.normal(-12, 3, 300), rng.normal(8, 3, 300)])
    fit = fit_marginal(x)
    assert fit.marginal.family == "kde"
    assert fit.score.bic is None and fit.score.ks_pvalue > 0.05
    for c in fit.candidates:
        if c.family == "normal":
            assert c.status == "rejected" and c.reason.startswith("KS p =")


def test_sec_6_4_lowest_bic_among_passing_families_wins() -> None:
    x = np.random.default_rng(4).uniform(-3.0, 5.0, 1000)
    fit = fit_marginal(x)
    passing = [c for c in fit.candidates if c.status == "fitted" and c.bic is not None]
    assert fit.marginal.family == "uniform"
    assert fit.score.bic == min(c.bic for c in passing)


def test_sec_6_4_kde_alone_is_chosen_without_a_gate() -> None:
    x = np.random.default_rng(5).normal(size=80)
    assert fit_marginal(x, families=(KDE,)).marginal.family == "kde"
    assert fit_marginal(x, families=(NORMAL, KDE)).marginal.family == "normal"


@pytest.mark.parametrize(
    ("values", "match"),
    [([1.0, np.nan, 2.0], "finite"), ([2.5] * 20, "2 distinct values"), ([1.0], "2 distinct")],
)
def test_sec_6_4_bad_values_are_input_error(values: list[float], match: str) -> None:
    with pytest.raises(InputError, match=match):
        fit_marginal(np.asarray(values), "x")


@pytest.mark.parametrize("family", [f.name for f in FAMILIES])
def test_sec_6_4_every_family_fits_and_round_trips(family: str) -> None:
    x = np.random.default_rng(6).gamma(5.0, 1.0, 200)
    fam = next(f for f in FAMILIES if f.name == family)
    fit = fit_marginal(x, families=(fam,), ks_alpha=0.0)
    assert fit.marginal.family == family and fit.candidates[0].status == "fitted"
    again = MarginalFit.from_dict(json.loads(json.dumps(fit.to_dict())))
    assert again == fit
    u = np.linspace(0.0, 1.0, 101)
    np.testing.assert_array_equal(again.marginal.quantile(u), fit.marginal.quantile(u))


@pytest.mark.parametrize("family", ["normal", "student_t", "kde"])
def test_sec_6_4_quantile_is_monotone_and_spans_the_bounds(family: str) -> None:
    x = np.random.default_rng(7).normal(0.0, 1.0, 200)
    fam = next(f for f in FAMILIES if f.name == family)
    m = fit_marginal(x, families=(fam,), ks_alpha=0.0).marginal
    q = m.quantile(np.linspace(0.0, 1.0, 1001))
    assert np.all(np.diff(q) >= 0)
    assert q[0] == pytest.approx(m.bounds[0], abs=1e-6)
    assert q[-1] == pytest.approx(m.bounds[1], abs=1e-6)
    width = np.ptp(x)
    assert m.bounds == pytest.approx((x.min() - 0.1 * width, x.max() + 0.1 * width))


@pytest.mark.parametrize(
    ("desc", "match"),
    [
        ({"family": "lognormal", "params": {}, "bounds": [0, 1]}, "unknown marginal family"),
        ({"family": "normal", "params": {"loc": 0}, "bounds": [0, 1]}, "params must be"),
        ({"family": "normal", "params": {"loc": 0, "scale": 1}, "bounds": [1, 0]}, "lo < hi"),
        ({"family": "kde", "params": {"bw_factor": 0.3}, "bounds": [0, 1]}, "at least 2 points"),
        ({"family": "normal", "params": {"loc": 0, "scale": -1}, "bounds": [0, 1]}, "no prob"),
        ({"family": "uniform", "params": {"loc": 5, "scale": 1}, "bounds": [0, 1]}, "no prob"),
    ],
)
def test_sec_6_4_bad_marginal_description_is_input_error(desc: dict, match: str) -> None:
    with pytest.raises(InputError, match=match):
        Marginal.from_dict(desc)
