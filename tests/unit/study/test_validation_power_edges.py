"""What a validation's n can show (Sec. 6.7), where the mutation run (issue 40) found it
open: the smallest n against a brute-force scan of Newcombe's method 10 written out here
(Wilson score bounds combined by square-and-add, k = p·n), at two confidence levels; a
difference too small for `N_MAX`; the shares around the pooled share (`_around`); the
summary's fields for one comparison, at a level other than 95 %, with n exactly the needed
one; and the exact text of the power note in each of its forms.
"""

from __future__ import annotations

import math

import pytest
from scipy.stats import norm

from transfertwin._errors import InputError
from transfertwin.study.validation import StateComparison, n_to_exclude_zero
from transfertwin.study.validation._power import (
    PowerSummary,
    _around,
    power_note,
    power_summary,
)


def _newcombe_excludes_zero(p1: float, p2: float, n: int, alpha: float) -> bool:
    """Newcombe (1998) method 10 with k = p·n, written out."""
    z = norm.ppf(1 - alpha / 2)

    def wilson(p: float) -> tuple[float, float]:
        centre = (p + z * z / (2 * n)) / (1 + z * z / n)
        half = z * math.sqrt(p * (1 - p) / n + z * z / (4 * n * n)) / (1 + z * z / n)
        return centre - half, centre + half

    (l1, u1), (l2, u2) = wilson(p1), wilson(p2)
    d = p1 - p2
    low = d - math.sqrt((p1 - l1) ** 2 + (u2 - p2) ** 2)
    high = d + math.sqrt((u1 - p1) ** 2 + (p2 - l2) ** 2)
    return low > 0 or high < 0


def _scan(p1: float, p2: float, alpha: float, n_max: int = 2000) -> int:
    return next(n for n in range(1, n_max) if _newcombe_excludes_zero(p1, p2, n, alpha))


PAIRS = [(1.0, 0.0), (0.9, 0.3), (0.8, 0.5), (0.6, 0.4), (0.3, 0.05), (0.55, 0.45), (0.7, 0.6)]


@pytest.mark.parametrize("alpha", [0.05, 0.01])
@pytest.mark.parametrize(("p1", "p2"), PAIRS)
def test_sec_6_7_smallest_n_matches_a_scan_of_the_written_out_interval(p1, p2, alpha) -> None:
    assert n_to_exclude_zero(p1, p2, alpha) == _scan(p1, p2, alpha)


def test_sec_6_7_a_difference_no_n_up_to_n_max_can_show_is_none() -> None:
    assert n_to_exclude_zero(0.5, 0.5001) is None  # needs about 2e8 runs per side


@pytest.mark.parametrize(
    ("p", "d", "shares"),
    [(0.5, 0.2, (0.6, 0.4)), (0.05, 0.2, (0.2, 0.0)), (0.97, 0.2, (1.0, 0.8)),
     (0.3, 0.5, (0.55, 0.05))],
)  # fmt: skip
def test_sec_6_7_shares_around_the_pooled_share_stay_in_0_1(p, d, shares) -> None:
    assert _around(p, d) == pytest.approx(shares, abs=1e-12)


def _comparison(k_v: int, n_v: int, k_p: int, n_p: int, low: float, high: float,
                alpha: float = 0.05) -> StateComparison:  # fmt: skip
    return StateComparison("o1", "front", "left", 0, n_v, k_v, 0.0, 1.0, n_p, k_p, 0.0, 1.0,
                           low, high, alpha)  # fmt: skip


def test_sec_6_7_power_summary_of_one_comparison_at_99_percent() -> None:
    """9/10 against 3/10: the pooled share 0.6 gives shares 0.7 and 0.5 for the detectable
    difference 0.2; the observed shares are 0.9 and 0.3."""
    c = _comparison(9, 10, 3, 10, -0.1, 0.3, alpha=0.01)
    s = power_summary([c])
    assert s.alpha == 0.01 and s.detectable == 0.2
    assert s.n_detectable == (_scan(0.7, 0.5, 0.01),)
    assert s.n_observed == (_scan(0.9, 0.3, 0.01),)
    assert s.half_width == (pytest.approx(0.2),)
    assert s.underpowered == (True,)
    assert s.to_dict() == {
        "detectable_difference": 0.2, "alpha": 0.01, "states_underpowered": 1,
        "n_per_side_detectable": [s.n_detectable[0]], "n_per_side_observed": [s.n_observed[0]],
        "underpowered": [True],
    }  # fmt: skip


def test_sec_6_7_n_equal_to_the_needed_n_is_not_underpowered() -> None:
    need = _scan(0.6, 0.4, 0.05)
    k = need // 2
    c = _comparison(need - k, need, k, need, -0.05, 0.05)  # pooled share 1/2
    assert power_summary([c]).n_detectable == (need,)
    assert power_summary([c]).underpowered == (False,)
    fewer = _comparison(need - 1 - k, need - 1, k, need - 1, -0.05, 0.05)
    assert power_summary([fewer]).underpowered == (True,)


@pytest.mark.parametrize("detectable", [1.0, 0.5])
def test_sec_6_7_a_detectable_difference_up_to_one_is_allowed(detectable: float) -> None:
    assert power_summary([_comparison(1, 2, 1, 2, -0.8, 0.8)], detectable).detectable == detectable


@pytest.mark.parametrize("detectable", [0.0, 1.0001, 2.0])
def test_sec_6_7_a_detectable_difference_outside_0_1_is_refused(detectable: float) -> None:
    with pytest.raises(InputError, match=r"must lie in \(0, 1\]"):
        power_summary([_comparison(1, 2, 1, 2, -0.8, 0.8)], detectable)


def _summary(underpowered, n_det, n_obs, alpha=0.05) -> PowerSummary:
    k = len(underpowered)
    return PowerSummary(n_v=(10, 20, 30)[:k], n_p=(1, 2, 3)[:k], half_width=(0.5, 0.3, 0.1)[:k],
                        n_detectable=n_det, n_observed=n_obs, underpowered=underpowered,
                        detectable=0.2, alpha=alpha)  # fmt: skip


def test_sec_6_7_power_note_texts() -> None:
    assert power_note(_summary((False, False), (5, 5), (5, 5))) == ""
    assert power_note(_summary((True, False, True), (90, 5, 110), (None, 5, 7))) == (
        "2/3 compared states have too few runs to see a difference: physical n = 1–3 per "
        "state, virtual n = 10–30, difference intervals ±0.30 on average, so 'not significant' "
        "there does not mean 'no difference'. A 95 % Newcombe interval would exclude 0 for a "
        "difference of 0.2 with n = 90–110 per side; for the observed differences with n = 7 "
        "per side."
    )
    assert power_note(_summary((True, True, True), (None, None, None), (4, 9, 6), 0.01)) == (
        "no power at this n: physical n = 1–3 per state, virtual n = 10–30, difference "
        "intervals ±0.30 on average, so 'not significant' there does not mean 'no "
        "difference'. A 99 % Newcombe interval would exclude 0 for the observed differences "
        "with n = 4–9 per side."
    )
    assert power_note(_summary((True,), (None,), (None,))) == (
        "no power at this n: physical n = 1 per state, virtual n = 10, difference intervals "
        "±0.50 on average, so 'not significant' there does not mean 'no difference'."
    )
