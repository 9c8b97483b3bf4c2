"""Edges of the full-state analysis (Sec. 6.6–6.7) that the mutation run (issue 40) found
open: Clopper–Pearson intervals at two confidence levels against their definition (beta
quantiles from scipy, not statsmodels), scalar and vectorised, with the fields of the n = 0
interval and the wording of bad counts; the window bounds of Eq. 6.27; `analyze` and
`select` passing their window on; objects in natural order, an object without an 'ok' run
skipped without stopping the others; the exact text of ``states.csv`` and
``selection.json``.
"""

from __future__ import annotations

import json
import math
from fractions import Fraction

import numpy as np
import pytest
from scipy.stats import beta

from transfertwin._errors import InputError
from transfertwin.study.fullstate import _states as fullstate_states
from transfertwin.study.fullstate import (
    analyze,
    clopper_pearson,
    clopper_pearson_array,
    moving_average,
    object_sort_key,
    select,
    series_table,
    state_table,
)
from transfertwin.study.fullstate._analysis import selection_json_text, states_csv_text
from transfertwin.study.fullstate._selection import CircularSeries

LEVELS = (0.05, 0.01)


def cp(k: int, n: int, alpha: float) -> tuple[float, float]:
    """Clopper–Pearson bounds by their definition (Clopper & Pearson 1934)."""
    low = 0.0 if k == 0 else beta.ppf(alpha / 2, k, n - k + 1)
    high = 1.0 if k == n else beta.ppf(1 - alpha / 2, k + 1, n - k)
    return float(low), float(high)


@pytest.mark.parametrize("alpha", LEVELS)
def test_sec_6_7_clopper_pearson_at_two_levels_scalar_and_array(alpha: float) -> None:
    ks, ns = np.array([0, 3, 9, 10, 0, 1]), np.array([10, 10, 10, 10, 0, 1])
    low, high = clopper_pearson_array(ks, ns, alpha)
    for i, (k, n) in enumerate(zip(ks.tolist(), ns.tolist(), strict=True)):
        one = clopper_pearson(k, n, alpha)
        assert (one.k, one.n, one.alpha, one.method) == (k, n, alpha, "clopper-pearson")
        if n == 0:
            assert math.isnan(one.low) and math.isnan(one.high)
            assert math.isnan(low[i]) and math.isnan(high[i])
            continue
        assert (one.low, one.high) == pytest.approx(cp(k, n, alpha), abs=1e-9)
        assert (low[i], high[i]) == pytest.approx(cp(k, n, alpha), abs=1e-9)
    assert low[3] == pytest.approx((alpha / 2) ** 0.1, abs=1e-12)  # k = n: (α/2)^(1/n)


def test_sec_6_7_an_interval_without_trials_keeps_its_counts_and_level() -> None:
    empty = clopper_pearson(0, 0, 0.01)
    assert (empty.method, empty.k, empty.n, empty.alpha) == ("clopper-pearson", 0, 0, 0.01)
    assert math.isnan(empty.p_hat) and empty.confidence == pytest.approx(0.99)


@pytest.mark.parametrize(
    ("k", "n", "message"),
    [(-1, 2, r"^Clopper-Pearson: k must be a non-negative integer, got -1$"),
     (1, 2.0, r"^Clopper-Pearson: n must be a non-negative integer, got 2\.0$")],
)  # fmt: skip
def test_sec_6_7_bad_counts_name_the_count(k: object, n: object, message: str) -> None:
    with pytest.raises(InputError, match=message):
        clopper_pearson(k, n)


@pytest.mark.parametrize(
    ("k", "n", "message"),
    [(np.array([-1]), np.array([2]), r"^Clopper-Pearson: k must hold non-negative integers$"),
     (np.array([1]), np.array([2.0]), r"^Clopper-Pearson: n must hold non-negative integers$")],
)  # fmt: skip
def test_sec_6_7_bad_count_arrays_name_the_array(k, n, message: str) -> None:
    with pytest.raises(InputError, match=message):
        clopper_pearson_array(k, n)


@pytest.mark.parametrize("alpha", ["0.05", None, True])
def test_sec_6_7_alpha_must_be_a_real_number(alpha: object) -> None:
    with pytest.raises(InputError, match="alpha must be a number in"):
        clopper_pearson(1, 2, alpha)


@pytest.mark.parametrize("window", [1, 361])
def test_eq_6_27_window_bounds_are_inclusive(window: int) -> None:
    y = CircularSeries((0, 10, 20), (Fraction(1), Fraction(0), Fraction(1)))
    out = moving_average(y, window)
    assert len(out.values) == 3
    if window == 1:
        assert out.values == y.values  # a window of one degree is the series itself


@pytest.mark.parametrize("window", [-1, 0, 2, 363])
def test_eq_6_27_window_outside_1_to_361_or_even_is_refused(window: int) -> None:
    y = CircularSeries((0, 10), (Fraction(1), Fraction(0)))
    with pytest.raises(InputError, match=r"odd integer in 1\.\.361"):
        moving_average(y, window)


def _row(obj: str, face: str, conveyor: str, theta: int, success: int, status: str = "ok"):
    return {"object_id": obj, "face": face, "conveyor": conveyor, "theta_deg": theta,
            "success": success, "status": status}  # fmt: skip


def _rows() -> list[dict]:
    """o2 on the front/left series: success at θ 0 and 5, failure at 10 and 15; o10 the
    other way round; o3 run only with an invalid result."""
    out = [_row("o10", "front", "left", t, int(t > 8)) for t in (0, 5, 10, 15)]  # the mirror
    out += [_row("o2", "front", "left", t, int(t < 8)) for t in (0, 5, 10, 15)]
    out.append(_row("o3", "front", "left", 0, 0, "invalid"))
    return out


def test_sec_6_6_analyze_passes_its_window_and_skips_only_the_empty_object() -> None:
    narrow = analyze(_rows(), window=1)
    assert narrow.window == 1 and narrow.object_ids == ("o2", "o10")
    assert narrow.skipped_objects == ("o3",)
    assert [s.object_id for s in narrow.selections] == ["o2", "o10"]
    (series,) = narrow.series_of("o2")
    assert series.y_ma == (1, 1, 0, 0)  # window 1: ȳ^MA = ȳ
    assert narrow.series_of("o10")[0].y_ma == (0, 0, 1, 1)
    wide = analyze(_rows(), window=21)  # θ ± 10°: the mean of the run angles within it
    assert wide.series_of("o2")[0].y_ma == (Fraction(2, 3), Fraction(1, 2), Fraction(1, 2),
                                            Fraction(1, 3))  # fmt: skip
    assert narrow.selection_of("o10").object_id == "o10"
    states = state_table(_rows())
    assert select(states, "o2", window=1) == narrow.selection_of("o2")
    assert select(states, "o2", window=21) == wide.selection_of("o2")


def test_sec_6_6_states_csv_and_selection_json_texts() -> None:
    result = analyze(_rows(), window=1)
    text = states_csv_text(result)
    assert "\r" not in text
    lines = text.split("\n")
    assert lines[1] == "o2,front,left,0,1,1,1.0,1.0,,0.025,1.0"
    assert lines[3] == "o2,front,left,10,1,0,0.0,0.0,,0.0,0.975"
    assert lines[5] == "o3,front,left,0,0,0,,,,,"  # natural order: o2, o3, o10
    js = selection_json_text(result)
    assert js.startswith('{\n  "o2": {\n    "') and js.endswith("}\n")
    assert list(json.loads(js)) == ["o2", "o10"]


def test_eq_6_27_the_default_window_is_21_degrees() -> None:
    y = CircularSeries((0, 10, 20, 30), (Fraction(1), Fraction(0), Fraction(1), Fraction(1)))
    assert moving_average(y) == moving_average(y, 21)


def test_eq_6_27_a_series_needs_strictly_ascending_angles() -> None:
    with pytest.raises(InputError):
        CircularSeries((0, 0), (Fraction(1), Fraction(0)))
    s = CircularSeries([np.int64(0), np.int64(10)], [1, 0])
    assert s.theta_deg == (0, 10) and all(type(t) is int for t in s.theta_deg)


def test_eq_6_26_rows_parse_empty_status_string_success_and_missing_object() -> None:
    as_text = {**_row("o1", "front", "left", 0, 0), "success": "0"}
    rows = [_row("o1", "front", "left", 0, 1, ""), as_text]
    (st,) = state_table(rows)
    assert (st.n, st.k) == (2, 1)
    with pytest.raises(InputError, match="empty object_id"):
        state_table([{**_row("o1", "front", "left", 0, 1), "object_id": None}])


def test_sec_6_6_object_ids_with_letters_and_digits_sort_naturally() -> None:
    ids = ["ob", "o10", "o2", "oa"]
    assert sorted(ids, key=object_sort_key) == ["o2", "o10", "oa", "ob"]


def test_eq_6_7_labels_seen_before_parse_the_same_the_second_time(monkeypatch) -> None:
    monkeypatch.setattr(fullstate_states, "_STATE_CACHE", {})  # the first lookup is a miss
    rows = [{**_row("o1", "front", "left", 0, 1), "face": "  FrOnT ", "theta_deg": 7}] * 2
    first, second = state_table(rows[:1]), state_table(rows)
    assert first[0].key == second[0].key == ("o1", "front", "left", 7)
    assert second[0].n == 2


def test_eq_6_28_a_missing_series_does_not_end_the_list_and_records_are_kept() -> None:
    rows = [_row("o1", "front", "left", 0, 1), _row("o1", "back", "left", 0, 0)]
    series = series_table(state_table(rows), "o1", window=1)
    assert [(s.face, s.side) for s in series] == [("front", "left"), ("back", "left")]
    result = analyze(rows, window=1)
    assert len(result.records) == 2 and result.records[1].face == "back"


def test_eq_6_27_a_361_degree_window_is_the_mean_of_the_whole_series_once() -> None:
    y = CircularSeries((0, 10, 180), (Fraction(1), Fraction(0), Fraction(1)))
    assert moving_average(y, 361).values == (Fraction(2, 3),) * 3  # θ = 180 counted once
    best = select(state_table(_rows()), "o2", window=361).best
    assert best.theta_deg == 0  # every ȳ^MA ties: the lowest θ


def test_eq_6_26_series_values_must_be_real_numbers() -> None:
    with pytest.raises(InputError):
        CircularSeries((0, 10), ("1", Fraction(0)))
