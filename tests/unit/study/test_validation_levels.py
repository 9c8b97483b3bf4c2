"""Every interval of the validation (Sec. 6.7) at two confidence levels against independent
numbers, the edge rows of a validation and every count of ``summary.json``.

Independent numbers: the Clopper–Pearson bounds are the beta quantiles of their definition
(Clopper & Pearson 1934; low = B(α/2; k, n−k+1), high = B(1−α/2; k+1, n−k)) from scipy, and
at k = n the closed form (α/2)^(1/n); the Newcombe hybrid score bounds (Newcombe 1998,
method 10) are written out from two Wilson score intervals with scipy's normal quantile;
at 95 % 9/10 − 3/10 is the published [0.1705, 0.8090] (Table II, example (b)). None comes
from statsmodels, which the code under test calls.

Edge rows: a state whose virtual runs all errored but which ran physically is compared
nowhere and counted as physical-only (and the mirror case as virtual-only).

Last, the pure parts of the scene-agreement check (`_agreement`): what counts as a success,
when two shares agree (each inside the other's Clopper–Pearson interval) and its summary line.
"""

from __future__ import annotations

import json
import logging
import math

import pytest
from scipy.stats import beta, norm

from transfertwin._errors import InputError
from transfertwin.study.experiment import ExperimentResult
from transfertwin.study.validation._agreement import Agreement, SideOutcome, _outcome
from transfertwin.study.validation._validation import (
    ValidationResult,
    compare,
    newcombe_difference,
    summary_json_text,
    validate,
    validation_csv_text,
)

A = ("o1", "front", "left", 0)  # 9/10 virtual vs 3/10 physical
B = ("o1", "back", "both", 90)  # 5/10 vs 5/10
C = ("o2", "front", "right", 0)  # 10/10 vs 8/10
ERRORED_V = ("o3", "front", "both", 45)  # every virtual run errored; 2/2 physically
ERRORED_P = ("o2", "front", "both", 60)  # 1/3 virtually; every physical row invalid
ONE_RUN = ("o10", "front", "left", 0)  # one run a side: n = 1, object after o3 (natural)
LEVELS = (0.05, 0.01)


def rows(state: tuple, k: int, n: int, status: str = "ok") -> list[dict]:
    obj, face, conveyor, theta = state
    return [{"object_id": obj, "face": face, "conveyor": conveyor, "theta_deg": theta,
             "success": int(i < k), "status": status} for i in range(n)]  # fmt: skip


def virtual() -> list[dict]:
    return [*rows(A, 9, 10), *rows(B, 5, 10), *rows(C, 10, 10), *rows(ERRORED_V, 0, 4, "error"),
            *rows(ERRORED_P, 1, 3), *rows(ONE_RUN, 1, 1)]  # fmt: skip


def physical() -> list[dict]:
    return [*rows(A, 3, 10), *rows(B, 5, 10), *rows(C, 8, 10), *rows(ERRORED_V, 2, 2),
            *rows(ERRORED_P, 0, 2, "invalid"), *rows(ONE_RUN, 0, 1)]  # fmt: skip


def cp(k: int, n: int, alpha: float) -> tuple[float, float]:
    """Clopper–Pearson bounds from their definition (beta quantiles)."""
    low = 0.0 if k == 0 else beta.ppf(alpha / 2, k, n - k + 1)
    high = 1.0 if k == n else beta.ppf(1 - alpha / 2, k + 1, n - k)
    return float(low), float(high)


def wilson(k: int, n: int, z: float) -> tuple[float, float]:
    p = k / n
    centre = (p + z * z / (2 * n)) / (1 + z * z / n)
    half = z * math.sqrt(p * (1 - p) / n + z * z / (4 * n * n)) / (1 + z * z / n)
    return centre - half, centre + half


def newcombe(k1: int, n1: int, k2: int, n2: int, alpha: float) -> tuple[float, float]:
    """Newcombe (1998) method 10, square-and-add of two Wilson intervals."""
    z = norm.ppf(1 - alpha / 2)
    (l1, u1), (l2, u2) = wilson(k1, n1, z), wilson(k2, n2, z)
    p1, p2 = k1 / n1, k2 / n2
    d = p1 - p2
    return (d - math.sqrt((p1 - l1) ** 2 + (u2 - p2) ** 2),
            d + math.sqrt((u1 - p1) ** 2 + (p2 - l2) ** 2))  # fmt: skip


COUNTS = {A: (9, 10, 3, 10), B: (5, 10, 5, 10), C: (10, 10, 8, 10), ONE_RUN: (1, 1, 0, 1)}


@pytest.mark.parametrize("alpha", LEVELS)
def test_sec_6_7_every_interval_at_two_levels_matches_independent_numbers(alpha: float) -> None:
    comps = compare(virtual(), physical(), alpha=alpha)
    assert [c.key for c in comps] == [A, B, C, ONE_RUN]
    for c in comps:
        k_v, n_v, k_p, n_p = COUNTS[c.key]
        assert (c.k_v, c.n_v, c.k_p, c.n_p, c.alpha) == (k_v, n_v, k_p, n_p, alpha)
        assert (c.ci_v_low, c.ci_v_high) == pytest.approx(cp(k_v, n_v, alpha), abs=1e-9)
        assert (c.ci_p_low, c.ci_p_high) == pytest.approx(cp(k_p, n_p, alpha), abs=1e-9)
        low, high = newcombe(k_v, n_v, k_p, n_p, alpha)
        assert (c.diff_low, c.diff_high) == pytest.approx((low, high), abs=1e-9)
        assert c.significant is (low > 0 or high < 0)
        assert c.difference.alpha == alpha
    # 10/10 has the closed form low = (α/2)^(1/n)
    assert comps[2].ci_v_low == pytest.approx((alpha / 2) ** (1 / 10), abs=1e-12)
    # validate gives the same intervals and records the level
    result = validate(virtual(), physical(), alpha=alpha)
    assert result.comparisons == tuple(comps)
    assert result.alpha == alpha and result.to_dict()["alpha"] == alpha


def test_sec_6_7_the_levels_differ_where_they_should() -> None:
    at95, at99 = (compare(virtual(), physical(), alpha=a)[0] for a in LEVELS)
    assert (at95.diff_low, at95.diff_high) == pytest.approx((0.1705, 0.8090), abs=5e-5)
    assert at99.ci_p_high > at95.ci_p_high and at99.ci_p_low < at95.ci_p_low
    assert at99.ci_v_high > at95.ci_v_high and at99.diff_low < at95.diff_low


@pytest.mark.parametrize("alpha", LEVELS)
def test_sec_6_7_newcombe_difference_at_two_levels(alpha: float) -> None:
    # (g) of Newcombe's Table II: 10/10 - 0/20, whose upper bound reaches 1
    d = newcombe_difference(10, 10, 0, 20, alpha)
    low, high = newcombe(10, 10, 0, 20, alpha)
    assert (d.low, d.high) == pytest.approx((low, min(high, 1.0)), abs=1e-9)
    assert d.high <= 1.0 and d.estimate == 1.0 and d.alpha == alpha
    assert d.method == "newcombe-hybrid-score"
    m = newcombe_difference(0, 20, 10, 10, alpha)  # the mirror reaches -1
    assert (m.low, m.high) == pytest.approx((-d.high, -d.low), abs=1e-12)
    assert m.low >= -1.0


def test_sec_6_7_newcombe_needs_a_run_on_each_side() -> None:
    for args in ((0, 0, 1, 2), (1, 2, 0, 0)):
        with pytest.raises(InputError, match="needs n >= 1 on both sides"):
            newcombe_difference(*args)


def test_sec_6_7_all_errored_virtual_but_ran_physically_is_physical_only(caplog) -> None:
    with caplog.at_level(logging.INFO, logger="transfertwin.study.validation._validation"):
        result = validate(virtual(), physical())
    assert ERRORED_V not in [c.key for c in result.comparisons]
    assert result.physical_only == (ERRORED_V,)
    assert result.virtual_only == (ERRORED_P,)
    assert "1 physical-only states not compared" in caplog.text
    assert "1 virtual-only states not compared" in caplog.text
    summary = json.loads(summary_json_text(result))
    assert summary["objects"]["o3"] == {
        "states_compared": 0, "states_significant": 0, "states_virtual_only": 0,
        "states_physical_only": 1, "differs": None,
    }  # fmt: skip
    assert summary["objects"]["o2"]["states_virtual_only"] == 1


def test_sec_6_7_one_run_a_side_is_compared() -> None:
    comps = {c.key: c for c in compare(virtual(), physical())}
    one = comps[ONE_RUN]
    assert (one.n_v, one.k_v, one.n_p, one.k_p) == (1, 1, 1, 0)
    assert one.ci_v_low == pytest.approx(0.025)  # (α/2)^(1/1)


def test_sec_6_7_every_count_of_summary_json() -> None:
    result = validate(virtual(), physical(), alpha=0.01)
    text = summary_json_text(result)
    assert text.endswith("}\n") and text.startswith('{\n  "summary": ')  # indent 2
    s = json.loads(text)
    significant = [c.key for c in result.comparisons if c.significant]
    assert s == {
        "summary": f"{len({k[0] for k in significant})}/3 objects differ",
        "alpha": 0.01,
        "state_interval": "clopper-pearson",
        "difference_interval": "newcombe-hybrid-score",
        "difference": "p_v - p_p",
        "objects_compared": 3,
        "objects_differing": len({k[0] for k in significant}),
        "differing_objects": sorted({k[0] for k in significant}),
        "states_compared": 4,
        "states_significant": len(significant),
        "states_virtual_only": 1,
        "states_physical_only": 1,
        "objects": s["objects"],
        "power": s["power"],
        "power_note": result.power_note,
    }
    assert list(s["objects"]) == ["o1", "o2", "o3", "o10"]  # natural order, not "o10" < "o2"
    assert s["objects"]["o1"]["states_compared"] == 2
    assert s["objects"]["o10"]["states_compared"] == 1
    assert s["power"] == json.loads(json.dumps(result.to_dict()["power"]))
    assert s["power"] is not None


def test_sec_6_7_physical_only_states_sort_in_state_order() -> None:
    # object (natural), then face, conveyor (left, both, right), then θ
    first, second, back = ("o2", "back", "left", -10), ("o3", "front", "left", 0), ("o3", "back",
                                                                                   "left", -10)
    p = [*physical(), *rows(back, 1, 1), *rows(second, 1, 1), *rows(first, 1, 1)]
    assert validate(virtual(), p).physical_only == (first, second, ERRORED_V, back)


@pytest.mark.parametrize("alpha", [0.0, 1.0, -0.1, 1.5])
def test_sec_6_7_a_bad_level_is_refused_even_with_nothing_to_compare(alpha: float) -> None:
    with pytest.raises(InputError, match="alpha"):
        compare([], [], alpha=alpha)
    with pytest.raises(InputError, match="alpha"):
        validate(virtual(), physical(), alpha=alpha)


def test_sec_6_7_bad_virtual_input_names_the_virtual_side() -> None:
    bad = [{**rows(A, 1, 1)[0], "success": 7}]
    with pytest.raises(InputError, match=r"^virtual results: results row 1"):
        validate(bad, physical())


def test_sec_6_7_csv_rows_at_a_level() -> None:
    text = validation_csv_text(compare(virtual(), physical(), alpha=0.01))
    first = text.splitlines()[1].split(",")
    low, high = newcombe(9, 10, 3, 10, 0.01)
    assert float(first[10]) == pytest.approx(low, abs=1e-12)
    assert float(first[11]) == pytest.approx(high, abs=1e-12)


# --- the scene-agreement check's pure parts (study.validation._agreement) -------------


def _result(status: str, success: int | None):
    return ExperimentResult("o1", "front", "left", 0, 0, 1, 0.0, 0.0, 0.0, success, success,
                            success, 1.0, status)  # fmt: skip


def test_an_experiment_counts_as_a_success_only_when_ok_and_successful() -> None:
    assert [_outcome(_result(s, y)) for s, y in
            [("ok", 1), ("ok", 0), ("invalid", None), ("error", 1)]] == [1, 0, 0, 0]  # fmt: skip


def test_two_scenes_agree_when_each_share_is_in_the_others_interval() -> None:
    fast = SideOutcome(9, 10, 1, 500, 2.0, (1,) * 9 + (0,))
    ref = SideOutcome(3, 10, 0, 900, 4.0, (1, 1, 1) + (0,) * 7)
    assert fast.share == 0.9 and fast.rate == 5.0 and ref.rate == 2.5
    assert (fast.interval.low, fast.interval.high) == pytest.approx(cp(9, 10, 0.05), abs=1e-9)
    differ = Agreement("o1 front", fast, ref)
    assert not differ.agree and differ.paired_same == 4
    assert differ.line() == (
        "o1 front       n=  10  fast    9 =  90.0% [0.555, 0.997]  ref    3 =  30.0% "
        "[0.067, 0.652]  paired same  40.0%  DIFFER"
    )
    same = Agreement("x", fast, SideOutcome(8, 10, 0, 1, 0.0, (1,) * 8 + (0, 0)))
    assert same.agree and same.line().endswith("AGREE") and math.isnan(same.reference.rate)
    assert math.isnan(SideOutcome(0, 0, 0, 0, 1.0, ()).share)


def test_sec_6_7_a_bad_level_is_named_before_the_tables_are_compared() -> None:
    with pytest.raises(InputError, match="alpha"):
        validate(rows(A, 1, 2), rows(B, 1, 2), alpha=1.5)  # nothing in common, bad level


def test_sec_6_7_a_result_without_comparisons_has_no_power_entry() -> None:
    empty = ValidationResult(())
    assert empty.to_dict()["power"] is None and empty.power_note == ""
    assert empty.summary_line == "0/0 objects differ"
