"""Gaussian copula docking-error models (Sec. 6.4): determinism, round trips, bounds, errors."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from transfertwin._errors import InputError
from transfertwin.sim import DockingError
from transfertwin.study import DockingErrorModel
from transfertwin.study.docking._copula import (
    MIN_ROWS,
    GaussianCopula,
    PerStationCopula,
    copula_from_dict,
    normal_scores,
)
from transfertwin.study.docking._marginals import FAMILIES

FAST = tuple(f for f in FAMILIES if f.name in ("normal", "uniform", "kde"))


def _data(n: int = 200, seed: int = 0) -> np.ndarray:
    rng = np.random.default_rng(seed)
    x = rng.normal(-7.0, 3.5, n)
    y = -1.5 * (x + 7.0) + rng.normal(0.0, 6.0, n)
    theta = 1.2 + 0.02 * y + rng.normal(0.0, 0.6, n)
    return np.column_stack([x, y, theta])


@pytest.fixture(scope="module")
def model() -> GaussianCopula:
    return GaussianCopula.fit(_data())


def test_sec_6_4_same_seed_gives_identical_bits(model: GaussianCopula) -> None:
    assert model.sample_n(500, 42).tobytes() == model.sample_n(500, 42).tobytes()
    assert not np.array_equal(model.sample_n(500, 42), model.sample_n(500, 43))
    assert model.sample(9) == model.sample(9)


def test_sec_6_4_sample_is_the_first_row_in_metres_and_radians(model: GaussianCopula) -> None:
    x_mm, y_mm, t_deg = model.sample_n(1, 5)[0]
    err = model.sample(5)
    assert isinstance(err, DockingError)
    assert (err.x_m, err.y_m, err.theta_rad) == pytest.approx(
        (x_mm / 1000.0, y_mm / 1000.0, math.radians(t_deg))
    )


def test_sec_6_4_copula_satisfies_the_docking_model_protocol(model: GaussianCopula) -> None:
    assert isinstance(model, DockingErrorModel)
    assert model.describe() == model.to_dict()


def test_sec_6_4_json_round_trip_gives_identical_samples(model: GaussianCopula) -> None:
    desc = json.loads(json.dumps(model.describe()))
    again = copula_from_dict(desc)
    assert isinstance(again, GaussianCopula)
    assert again.to_dict() == model.to_dict()
    assert again.sample_n(1000, 3).tobytes() == model.sample_n(1000, 3).tobytes()


def test_sec_6_4_description_records_winner_params_score_and_criterion(model) -> None:
    desc = model.to_dict()
    assert desc["kind"] == "copula" and desc["n_fit"] == 200
    assert [m["column"] for m in desc["marginals"]] == [
        "dock_err_x_mm", "dock_err_y_mm", "dock_err_theta_deg"
    ]  # fmt: skip
    for m in desc["marginals"]:
        assert m["criterion"] == {"name": "bic-ks-gate", "ks_alpha": 0.05}
        assert {"bic", "ks_statistic", "ks_pvalue"} <= m["score"].keys()
        assert m["family"] in [c["family"] for c in m["candidates"] if c["status"] == "fitted"]
        assert len(m["candidates"]) == len(FAMILIES)


def test_normal_scores_are_probit_of_ranks_over_n_plus_one() -> None:
    data = np.array([[3.0], [1.0], [2.0], [2.0]])
    from scipy.stats import norm

    expected = norm.ppf(np.array([4.0, 1.0, 2.5, 2.5]) / 5.0)
    np.testing.assert_allclose(normal_scores(data)[:, 0], expected)


def test_sec_6_4_samples_stay_within_widened_observed_range() -> None:
    rng = np.random.default_rng(1)
    data = np.column_stack([rng.standard_t(2.0, 300), rng.normal(0, 1, 300), rng.random(300)])
    model = GaussianCopula.fit(data)
    synth = model.sample_n(20000, 0)
    width = np.ptp(data, axis=0)
    lo, hi = data.min(axis=0) - 0.1 * width, data.max(axis=0) + 0.1 * width
    assert np.all(synth >= lo) and np.all(synth <= hi)
    assert np.all(synth[:, 2] >= data[:, 2].min()) and np.all(synth[:, 2] <= data[:, 2].max())


def _stations() -> tuple[np.ndarray, list[str]]:
    parts, units = [], []
    for k, (name, n, y_mean) in enumerate(
        (("TU_A", 40, 6.0), ("TU_B", 30, -11.0), ("TU_C", 20, -13.0))
    ):
        d = _data(n, seed=10 + k)
        d[:, 1] += y_mean
        parts.append(d)
        units += [name] * n
    return np.vstack(parts), units


@pytest.fixture(scope="module")
def stations() -> PerStationCopula:
    data, units = _stations()
    return PerStationCopula.fit(data, units, families=FAST)


def test_sec_6_4_per_station_samples_every_unit_by_data_frequency(stations) -> None:
    values, units = stations.sample_with_units(6000, 8)
    assert values.shape == (6000, 3) and len(units) == 6000
    share = {u: units.count(u) / 6000 for u in stations.units}
    assert share == pytest.approx({"TU_A": 4 / 9, "TU_B": 3 / 9, "TU_C": 2 / 9}, abs=0.03)
    data, labels = _stations()
    drawn = np.asarray(units)
    for u in stations.units:
        y_real = data[np.asarray(labels) == u, 1].mean()
        assert values[drawn == u, 1].mean() == pytest.approx(y_real, abs=2.0)


def test_sec_6_4_per_station_round_trip_and_determinism(stations) -> None:
    again = copula_from_dict(json.loads(json.dumps(stations.describe())))
    assert isinstance(again, PerStationCopula) and again.units == stations.units
    assert again.sample_n(300, 4).tobytes() == stations.sample_n(300, 4).tobytes()
    assert stations.sample(4) == again.sample(4)
    assert isinstance(stations, DockingErrorModel)


def test_sec_6_4_per_station_unit_with_too_few_rows_is_input_error() -> None:
    data, units = _stations()
    units[-1] = "TU_Y"  # one row of its own
    with pytest.raises(InputError, match="unit TU_Y: need at least 10 rows"):
        PerStationCopula.fit(data, units, families=FAST)
    with pytest.raises(InputError, match="one transfer unit per row"):
        PerStationCopula.fit(data, units[:-1], families=FAST)


@pytest.mark.parametrize(
    ("data", "match"),
    [
        (_data(MIN_ROWS - 1), "at least 10 rows"),
        (_data()[:, :2], r"\(n, 3\) array"),
        (np.where(np.arange(600).reshape(200, 3) == 4, np.nan, _data()), "finite"),
        (np.column_stack([_data()[:, :2], np.ones(200)]), "2 distinct values"),
    ],
)
def test_sec_6_4_bad_fit_data_is_input_error(data: np.ndarray, match: str) -> None:
    with pytest.raises(InputError, match=match):
        GaussianCopula.fit(data)


@pytest.mark.parametrize(("n", "seed"), [(0, 1), (-3, 1), (2, -1), (2, 1.5)])
def test_sec_6_4_bad_sample_arguments_are_input_error(model, n: int, seed: int) -> None:
    with pytest.raises(InputError):
        model.sample_n(n, seed)


def _broken(model: GaussianCopula, path: tuple, value: object) -> dict:
    desc = json.loads(json.dumps(model.to_dict()))
    node = desc
    for key in path[:-1]:
        node = node[key]
    if value is KeyError:
        del node[path[-1]]
    else:
        node[path[-1]] = value
    return desc


@pytest.mark.parametrize(
    ("path", "value", "match"),
    [
        (("kind",), "gmm", "expected kind 'copula'"),
        (("version",), 99, "unsupported version"),
        (("correlation",), KeyError, "malformed"),
        (("correlation", 0, 1), 0.3, "symmetric"),
        (("marginals", 0, "family"), "lognormal", "unknown marginal family"),
        (("marginals", 1, "params"), {"loc": 0.0}, "params must be"),
        (("marginals", 2, "bounds"), [1.0, -1.0], "lo < hi"),
    ],
)
def test_sec_6_4_malformed_description_is_one_line_input_error(model, path, value, match) -> None:
    with pytest.raises(InputError, match=match) as info:
        copula_from_dict(_broken(model, path, value))
    assert "\n" not in str(info.value)


def test_sec_6_4_non_positive_definite_correlation_is_input_error(model) -> None:
    desc = model.to_dict()
    desc["correlation"] = [[1.0, 0.9, -0.9], [0.9, 1.0, 0.9], [-0.9, 0.9, 1.0]]
    with pytest.raises(InputError, match="not positive definite"):
        copula_from_dict(desc)
    with pytest.raises(InputError, match="expected a JSON object"):
        copula_from_dict([1, 2])  # type: ignore[arg-type]
