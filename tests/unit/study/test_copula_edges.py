"""Edges of the docking-error copula (Sec. 6.4) that the mutation run (issue 40) found open:
the fit passing its families, KS level and column names on and recording its row count, the
`MIN_ROWS` bound, the checks of a copula and a per-station copula at their bounds, the sample
count, and the exact texts of the errors a user sees for a bad model file or bad data.
"""

from __future__ import annotations

import numpy as np
import pytest

from transfertwin._errors import InputError
from transfertwin.study.docking._copula import (
    COLUMNS,
    MIN_ROWS,
    GaussianCopula,
    PerStationCopula,
    copula_from_dict,
)
from transfertwin.study.docking._marginals import FAMILIES

NORMAL = tuple(f for f in FAMILIES if f.name == "normal")
FAST = tuple(f for f in FAMILIES if f.name in ("normal", "uniform"))


def _data(n: int, seed: int = 0) -> np.ndarray:
    rng = np.random.default_rng(seed)
    x = rng.normal(-7.0, 3.5, n)
    y = -1.5 * (x + 7.0) + rng.normal(0.0, 6.0, n)
    return np.column_stack([x, y, 1.2 + 0.02 * y + rng.normal(0.0, 0.6, n)])


def test_sec_6_4_fit_records_its_rows_families_level_and_columns() -> None:
    cop = GaussianCopula.fit(_data(MIN_ROWS), families=NORMAL, ks_alpha=0.001)
    assert MIN_ROWS == 10 and cop.n_fit == 10
    assert [m.marginal.family for m in cop.marginals] == ["normal"] * 3
    assert [m.ks_alpha for m in cop.marginals] == [0.001] * 3
    assert [[c.family for c in m.candidates] for m in cop.marginals] == [["normal"]] * 3
    assert [c["column"] for c in cop.to_dict()["marginals"]] == list(COLUMNS)


def test_sec_6_4_too_few_rows_and_constant_columns_name_what_is_wrong() -> None:
    with pytest.raises(InputError, match=r"^docking errors: need at least 10 rows to fit a "
                                         r"copula, got 9$"):  # fmt: skip
        GaussianCopula.fit(_data(9), families=FAST)
    data = _data(12)
    data[:, 1] = 2.0
    with pytest.raises(InputError, match=r"^dock_err_y_mm: needs at least 2 distinct values"):
        GaussianCopula.fit(data, families=FAST)


def _copula() -> GaussianCopula:
    return GaussianCopula.fit(_data(40), families=FAST)


def test_sec_6_4_copula_checks_its_marginals_and_correlation() -> None:
    good = _copula()
    with pytest.raises(InputError, match=r"^copula: needs 3 marginals and a 3x3 correlation"):
        GaussianCopula(good.marginals[:2], good.correlation, 10)
    rho = [[1.0, 1.5, 0.0], [1.5, 1.0, 0.0], [0.0, 0.0, 1.0]]
    with pytest.raises(InputError, match=r"^copula: correlation must be symmetric with unit"):
        GaussianCopula(good.marginals, rho, 10)  # |ρ| > 1 is named as such
    singular = [[1.0, 1.0, 0.0], [1.0, 1.0, 0.0], [0.0, 0.0, 1.0]]
    with pytest.raises(InputError, match=r"^copula: correlation matrix is not positive definite"):
        GaussianCopula(good.marginals, singular, 10)


@pytest.mark.parametrize("n", [0, 1.0, True, "2"])
def test_sec_6_4_sample_count_must_be_a_positive_integer(n: object) -> None:
    with pytest.raises(InputError, match=r"^number of samples must be an integer >= 1"):
        _copula().sample_n(n, 0)  # type: ignore[arg-type]


def test_sec_6_4_sample_counts_as_numpy_integers() -> None:
    assert _copula().sample_n(np.int64(3), 0).shape == (3, 3)


def test_sec_6_4_per_station_copula_checks_at_its_bounds() -> None:
    c = _copula()
    ok = PerStationCopula(("TU_A", "TU_B"), (c, c), (1, 5))  # a count of 1 is allowed
    assert ok.by_unit == {"TU_A": c, "TU_B": c}
    for units, copulas, counts in [((), (), ()), (("TU_A",), (c, c), (1, 1))]:
        with pytest.raises(InputError, match=r"^per-station copula: units, copulas and counts"):
            PerStationCopula(units, copulas, counts)
    for units, counts in [(("TU_A", "TU_A"), (2, 3)), (("TU_A", "TU_B"), (0, 3))]:
        with pytest.raises(InputError, match=r"^per-station copula: units must be unique with "
                                             r"counts >= 1$"):  # fmt: skip
            PerStationCopula(units, (c, c), counts)


def test_sec_6_4_a_bad_model_description_says_what_it_got() -> None:
    with pytest.raises(InputError, match=r"^copula model: expected kind 'copula', got 'fixed'$"):
        copula_from_dict({"kind": "fixed", "version": 1})
    with pytest.raises(InputError, match=r"^copula model: expected kind 'copula', got 'list'$"):
        GaussianCopula.from_dict([])  # type: ignore[arg-type]
    with pytest.raises(InputError, match=r"^copula model: malformed description \(KeyError: "
                                         r"'marginals'\)$"):  # fmt: skip
        copula_from_dict({"kind": "copula", "version": 1})
    with pytest.raises(InputError, match=r"^per-station copula model: malformed description "
                                         r"\(KeyError: 'stations'\)$"):  # fmt: skip
        copula_from_dict({"kind": "copula-per-station", "version": 1})
    with pytest.raises(InputError, match=r"^copula model: unsupported version 2$"):
        copula_from_dict({"kind": "copula", "version": 2})


def test_sec_6_4_per_station_fit_passes_families_and_level_and_one_sample_is_the_first() -> None:
    data = np.vstack([_data(12, 1), _data(15, 2)])
    units = ["TU_A"] * 12 + ["TU_B"] * 15
    per = PerStationCopula.fit(data, units, families=NORMAL, ks_alpha=0.001)
    assert per.units == ("TU_A", "TU_B") and per.counts == (12, 15)
    for cop in per.copulas:
        assert [m.marginal.family for m in cop.marginals] == ["normal"] * 3
        assert [m.ks_alpha for m in cop.marginals] == [0.001] * 3
    one = per.sample(7)
    first = per.sample_n(1, 7)[0]
    assert (one.x_m, one.y_m) == pytest.approx((first[0] / 1000, first[1] / 1000))
    assert one.theta_rad == pytest.approx(np.radians(first[2]))
