"""Gaussian copula docking-error generator (Sec. 6.4, Eq. 6.19) against independent numbers.

Recovery: 5,000 draws from a KNOWN Gaussian copula, built here with scipy alone
(multivariate normal → Φ → known marginal PPFs), must give back the known correlation,
the known marginal families and parameters; samples of the fitted model must match
the known marginals (one-sample KS against the true CDF) and the closed-form Spearman
correlation of a Gaussian copula, ρ_S = (6/π)·asin(ρ/2).

Shipped data: synthetic samples of the model fitted to the 191 measured errors must
reproduce the measured Pearson correlations (within 0.1) and not be told apart from the
measured marginals by a two-sample KS test at the 1 % level.
"""

from __future__ import annotations

import csv
import math
from importlib import resources

import numpy as np
import pytest
from scipy import stats

from transfertwin.study.docking._copula import GaussianCopula, PerStationCopula

RHO = np.array([[1.0, 0.5, -0.3], [0.5, 1.0, 0.2], [-0.3, 0.2, 1.0]])
TRUE = (stats.norm(2.0, 3.0), stats.gamma(4.0, loc=-1.0, scale=0.5), stats.uniform(-2.0, 5.0))


@pytest.fixture(scope="module")
def known() -> tuple[np.ndarray, GaussianCopula]:
    z = stats.multivariate_normal(np.zeros(3), RHO).rvs(5000, random_state=12345)
    u = stats.norm.cdf(z)
    data = np.column_stack([d.ppf(u[:, j]) for j, d in enumerate(TRUE)])
    return data, GaussianCopula.fit(data)


@pytest.fixture(scope="module")
def shipped() -> tuple[np.ndarray, list[str]]:
    text = resources.files("transfertwin.data").joinpath("calibration_experiments.csv").read_text()
    rows = list(csv.DictReader(text.splitlines()))
    cols = ("dock_err_x_mm", "dock_err_y_mm", "dock_err_theta_deg")
    return np.array([[float(r[c]) for c in cols] for r in rows]), [r["transfer_unit"] for r in rows]


def test_eq_6_19_recovers_the_known_correlation(known) -> None:
    _, model = known
    assert np.abs(np.asarray(model.correlation) - RHO).max() < 0.05


def test_eq_6_19_recovers_the_known_marginal_families_and_parameters(known) -> None:
    _, model = known
    normal, gamma, uniform = (m.marginal for m in model.marginals)
    assert (normal.family, gamma.family, uniform.family) == ("normal", "gamma", "uniform")
    assert normal.params == pytest.approx((2.0, 3.0), abs=0.15)
    a, loc, scale = gamma.params
    assert a == pytest.approx(4.0, rel=0.15)
    assert a * scale + loc == pytest.approx(1.0, abs=0.05)  # mean of Γ(4, -1, 0.5)
    assert math.sqrt(a) * scale == pytest.approx(1.0, abs=0.05)  # its standard deviation
    assert uniform.params == pytest.approx((-2.0, 5.0), abs=0.02)


def test_eq_6_19_samples_follow_the_known_marginals_and_spearman(known) -> None:
    _, model = known
    synth = model.sample_n(5000, seed=2024)
    for j, dist in enumerate(TRUE):
        assert stats.kstest(synth[:, j], dist.cdf).pvalue > 0.01
    rho_s = 6.0 / math.pi * np.arcsin(RHO / 2.0)
    assert np.abs(stats.spearmanr(synth).statistic - rho_s).max() < 0.04


def test_sec_6_4_shipped_data_synthetic_matches_real(shipped) -> None:
    real, _ = shipped
    model = GaussianCopula.fit(real)
    synth = model.sample_n(5000, seed=7)
    diff = np.corrcoef(synth, rowvar=False) - np.corrcoef(real, rowvar=False)
    assert np.abs(diff).max() < 0.1
    for j in range(3):
        assert stats.ks_2samp(synth[:, j], real[:, j]).pvalue > 0.01


def test_sec_6_4_shipped_data_per_station_synthetic_matches_real(shipped) -> None:
    real, units = shipped
    model = PerStationCopula.fit(real, units)
    synth, drawn = model.sample_with_units(5000, seed=11)
    diff = np.corrcoef(synth, rowvar=False) - np.corrcoef(real, rowvar=False)
    assert np.abs(diff).max() < 0.1
    labels, drawn_arr = np.asarray(units), np.asarray(drawn)
    for j in range(3):
        assert stats.ks_2samp(synth[:, j], real[:, j]).pvalue > 0.01
    for unit in sorted(set(units)):  # the y error differs by unit (Sec. 6.3): kept per unit
        y_real, y_syn = real[labels == unit, 1], synth[drawn_arr == unit, 1]
        assert stats.ks_2samp(y_syn, y_real).pvalue > 0.01
