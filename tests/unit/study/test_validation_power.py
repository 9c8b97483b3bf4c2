"""What a validation's n can show (Sec. 6.7): `n_to_exclude_zero` and the power note.

Expected values are hand-derived or come from another formula, never from the code:
- 2/2 vs 0/2: Wilson 95 % bounds [0.3424, 1] and [0, 0.6576]; Newcombe's lower bound
  1 − √(0.6576² + 0.6576²) = 0.070 > 0, while 1/1 vs 0/1 (Wilson [0.2065, 1] and
  [0, 0.7935]) gives 1 − √(2 · 0.7935²) < 0: n = 2.
- Mid-range shares: the Wald sample size ⌈z² (p₁q₁ + p₂q₂) / d²⌉ (0.6 vs 0.4: 47), which
  the Newcombe interval (a little wider there) meets within a few runs.
"""

from __future__ import annotations

import math

import pytest

from transfertwin._errors import InputError
from transfertwin.study.validation import (
    StateComparison,
    n_to_exclude_zero,
    newcombe_difference,
    power_note,
    power_summary,
)

Z = 1.959963984540054


def wald_n(p1: float, p2: float) -> int:
    return math.ceil(Z**2 * (p1 * (1 - p1) + p2 * (1 - p2)) / (p1 - p2) ** 2)


def test_sec_6_7_opposite_outcomes_need_two_runs_per_side() -> None:
    assert n_to_exclude_zero(1.0, 0.0) == 2
    assert n_to_exclude_zero(0.0, 1.0) == 2


@pytest.mark.parametrize(("p1", "p2"), [(0.6, 0.4), (0.5, 0.3), (0.45, 0.55), (0.7, 0.4)])
def test_sec_6_7_mid_range_shares_meet_the_wald_sample_size(p1: float, p2: float) -> None:
    n = n_to_exclude_zero(p1, p2)
    assert n is not None and abs(n - wald_n(p1, p2)) <= 3


def test_sec_6_7_the_found_n_is_the_smallest_that_excludes_zero() -> None:
    n = n_to_exclude_zero(1.0, 0.5)  # k = n and n/2: integer counts at even n
    assert n is not None
    m = n if n % 2 == 0 else n + 1
    assert newcombe_difference(m, m, m // 2, m).excludes_zero
    assert not newcombe_difference(n - 2 + n % 2, n - 2 + n % 2, (n - 2 + n % 2) // 2,
                                   n - 2 + n % 2).excludes_zero  # fmt: skip


def test_sec_6_7_equal_shares_never_differ() -> None:
    assert n_to_exclude_zero(0.5, 0.5) is None


@pytest.mark.parametrize(("p1", "p2", "alpha"), [(1.2, 0.0, 0.05), (0.5, -0.1, 0.05),
                                                 (0.5, 0.4, 0.0), (0.5, 0.4, 1.0)])  # fmt: skip
def test_sec_6_7_bad_shares_or_alpha_are_input_errors(p1: float, p2: float, alpha: float) -> None:
    with pytest.raises(InputError, match=r"Sec\. 6\.7"):
        n_to_exclude_zero(p1, p2, alpha)


def comparison(oid: str, k_v: int, n_v: int, k_p: int, n_p: int) -> StateComparison:
    d = newcombe_difference(k_v, n_v, k_p, n_p)
    return StateComparison(oid, "front", "both", 0, n_v, k_v, 0.0, 1.0, n_p, k_p, 0.0, 1.0,
                           d.low, d.high)  # fmt: skip


def test_sec_6_7_one_physical_run_per_state_has_no_power() -> None:
    """The README's `validate` example: 50 virtual runs, 1 real run per state."""
    comps = [comparison("o1", 45, 50, 1, 1), comparison("o18", 10, 50, 0, 1)]
    power = power_summary(comps)
    assert power.underpowered == (True, True)
    assert power.n_observed[0] == n_to_exclude_zero(0.9, 1.0)
    note = power_note(power)
    assert note.startswith("no power at this n: physical n = 1 per state, virtual n = 50")
    assert "±0." in note
    assert f"difference of 0.2 with n = {min(power.n_detectable)}–{max(power.n_detectable)}" in note
    assert "for the observed differences with n = " in note


def test_sec_6_7_enough_runs_or_a_significant_state_gives_no_note() -> None:
    comps = [comparison("o1", 50, 100, 50, 100), comparison("o2", 20, 20, 0, 1)]
    power = power_summary(comps)
    assert power.underpowered == (False, False)
    assert power_note(power) == ""


def test_sec_6_7_power_needs_comparisons() -> None:
    with pytest.raises(InputError, match="no compared state"):
        power_summary([])
