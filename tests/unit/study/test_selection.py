"""Eq. 6.27 and Alg. 1–4 on hand-built series; expected values derived by hand."""

from __future__ import annotations

import random
from fractions import Fraction

import numpy as np
import pytest

from transfertwin._errors import InputError
from transfertwin.ots import THETA_ALL
from transfertwin.study.fullstate._selection import (
    CircularSeries,
    best_global,
    best_local,
    circular_moving_average,
    moving_average,
    worst_global,
    worst_local,
)


def full(default: float, **at: float) -> CircularSeries:
    """A 360-entry series with ``default`` everywhere except ``at`` (keys like ``m100``)."""
    values = {t: default for t in THETA_ALL}
    for key, v in at.items():
        values[int(key.replace("m", "-"))] = v
    return CircularSeries(THETA_ALL, tuple(values[t] for t in THETA_ALL))


def plateau(default: float, value: float, thetas: range | list[int]) -> CircularSeries:
    values = {t: default for t in THETA_ALL}
    for t in thetas:
        values[t] = value
    return CircularSeries(THETA_ALL, tuple(values[t] for t in THETA_ALL))


# --- Eq. 6.27 -------------------------------------------------------------------------


def test_eq_6_27_moving_average_wraps() -> None:
    # A single 1 at θ = 180: every θ within 10° (circularly) sees 1/21, others 0.
    ma = moving_average(full(0, **{"180": 1}), window=21)
    got = dict(zip(ma.theta_deg, ma.values, strict=True))
    for t in (-179, -170, 170, 180):
        assert got[t] == Fraction(1, 21)
    for t in (-169, 169, 0):
        assert got[t] == 0


def test_eq_6_27_float_form_matches_hand_values() -> None:
    values = np.zeros(360)
    values[THETA_ALL.index(-179)] = 1.0
    out = circular_moving_average(values, window=3)
    idx = {t: i for i, t in enumerate(THETA_ALL)}
    assert out[idx[180]] == pytest.approx(1 / 3)
    assert out[idx[-179]] == pytest.approx(1 / 3)
    assert out[idx[-178]] == pytest.approx(1 / 3)
    assert out[idx[-177]] == 0.0


def test_eq_6_27_missing_theta_uses_mean_of_present_values() -> None:
    # Present: θ = 0, 5, 10, 15, 180 with values 1, 0, 1, 0, 1; window ±10°.
    s = CircularSeries((0, 5, 10, 15, 180), (1, 0, 1, 0, 1))
    ma = moving_average(s, window=21).values
    # θ=0 sees {0, 5, 10} -> 2/3; θ=5 sees {0..15} -> 1/2; θ=10 sees {0..15} -> 1/2;
    # θ=15 sees {5, 10, 15} -> 1/3; θ=180 sees only itself -> 1.
    assert ma == (Fraction(2, 3), Fraction(1, 2), Fraction(1, 2), Fraction(1, 3), Fraction(1))


def test_eq_6_27_float_form_keeps_nan_for_missing() -> None:
    values = np.full(360, np.nan)
    values[THETA_ALL.index(0)] = 1.0
    values[THETA_ALL.index(4)] = 0.0
    out = circular_moving_average(values)
    assert out[THETA_ALL.index(0)] == pytest.approx(0.5)
    assert np.isnan(out[THETA_ALL.index(2)])


def test_eq_6_27_agrees_with_brute_force_over_random_gaps() -> None:
    rng = random.Random(7)
    thetas = tuple(sorted(rng.sample(THETA_ALL, 90)))
    values = tuple(Fraction(rng.randint(0, 50), 50) for _ in thetas)
    ma = moving_average(CircularSeries(thetas, values), window=21).values
    for t, m in zip(thetas, ma, strict=True):
        near = [
            v
            for u, v in zip(thetas, values, strict=True)
            if min(abs(u - t), 360 - abs(u - t)) <= 10
        ]
        assert m == sum(near, Fraction(0)) / len(near)


@pytest.mark.parametrize("window", [0, 20, 363, 2.0, True])
def test_eq_6_27_bad_window_raises(window: object) -> None:
    with pytest.raises(InputError, match=r"Eq\. 6\.27"):
        moving_average(full(0), window=window)  # type: ignore[arg-type]


def test_eq_6_25_series_must_ascend_and_be_finite() -> None:
    with pytest.raises(InputError, match="ascending"):
        CircularSeries((3, 1), (0, 0))
    with pytest.raises(InputError, match="finite"):
        CircularSeries((1, 3), (0, float("nan")))
    with pytest.raises(InputError):
        CircularSeries((), ())


# --- Alg. 1 / 4 (local) ---------------------------------------------------------------


def test_alg_1_single_maximum() -> None:
    choice = best_local(full(0.25, **{"42": 0.75}))
    assert (choice.theta_deg, choice.value, choice.half_window) == (42, Fraction(3, 4), 0)


def test_alg_1_plateau_needs_widening_window() -> None:
    # Plateau of ones at θ = 10..14. h=1: 11, 12, 13 keep mean 1 (10, 14 drop to 2/3);
    # h=2: 12 keeps 1, 11 and 13 drop to 4/5.
    choice = best_local(plateau(0, 1, range(10, 15)))
    assert (choice.theta_deg, choice.value, choice.half_window) == (12, 1, 2)


def test_alg_1_neighbours_decide_at_first_widening() -> None:
    # Maxima at -100 and 50; h=1 sums: -100 -> 0.5+1+0.5 = 2, 50 -> 0.5+1+0.75 = 2.25.
    s = full(0, m101=0.5, m100=1, m99=0.5, **{"49": 0.5, "50": 1, "51": 0.75})
    choice = best_local(s)
    assert (choice.theta_deg, choice.half_window) == (50, 1)


def test_alg_1_all_equal_series_ties_to_lowest_theta() -> None:
    choice = best_local(full(0.5))
    assert (choice.theta_deg, choice.value, choice.half_window) == (-179, Fraction(1, 2), 180)


def test_alg_1_symmetric_plateau_ties_to_lowest_theta_at_full_circle() -> None:
    # Plateau 10..13: h=1 keeps 11 and 12, whose windows then hold equal sums for
    # every h < 180; at the full circle the lower θ (11) wins.
    choice = best_local(plateau(0, 1, range(10, 14)))
    assert (choice.theta_deg, choice.half_window) == (11, 180)


def test_alg_1_wraps_around_180() -> None:
    # Plateau 178, 179, 180, -179, -178 is contiguous on the circle; its centre is 180.
    choice = best_local(plateau(0, 1, [178, 179, 180, -179, -178]))
    assert (choice.theta_deg, choice.half_window) == (180, 2)


def test_alg_1_ties_are_exact_not_float_order_dependent() -> None:
    # Mirror-image neighbourhoods: every window sum is equal in exact arithmetic,
    # but summed left to right in floats the h=2 sums differ (1.5999999999999999 vs 1.6).
    assert 0.3 + 0.1 + 1.0 + 0.2 != 0.2 + 1.0 + 0.1 + 0.3
    s = full(
        0, m102=0.3, m101=0.1, m100=1.0, m99=0.2, **{"49": 0.2, "50": 1.0, "51": 0.1, "52": 0.3}
    )
    choice = best_local(s)
    assert (choice.theta_deg, choice.half_window) == (-100, 180)


def test_alg_1_on_sparse_series_uses_present_neighbours() -> None:
    # θ step 5: maxima at 0 and 90; h=5 sees {-5, 0, 5} -> (0.5+1+0)/3 and {85, 90, 95} ->
    # (0.5+1+0.5)/3, so 90 wins; h=1..4 see only the centres (ties).
    thetas = tuple(range(-175, 181, 5))
    vals = {t: 0.0 for t in thetas} | {-5: 0.5, 0: 1.0, 85: 0.5, 90: 1.0, 95: 0.5}
    choice = best_local(CircularSeries(thetas, tuple(vals[t] for t in thetas)))
    assert (choice.theta_deg, choice.half_window) == (90, 5)


def test_alg_4_worst_plateau_needs_widening_window() -> None:
    choice = worst_local(plateau(1, 0, range(-20, -15)))
    assert (choice.theta_deg, choice.value, choice.half_window) == (-18, 0, 2)


# --- Alg. 2 / 3 (global) --------------------------------------------------------------


def test_alg_2_highest_value_wins_over_half_window() -> None:
    series = [full(0.9), full(0, **{"5": 1.0}), full(0.2), full(0.2)]
    g = best_global(series)
    assert (g.series_index, g.local.theta_deg, g.local.half_window) == (1, 5, 0)


def test_alg_2_tie_goes_to_larger_half_window() -> None:
    series = [full(0, **{"0": 1.0}), plateau(0, 1, range(30, 35)), full(0.5), full(0.5)]
    g = best_global(series)
    assert (g.series_index, g.local.theta_deg, g.local.half_window) == (1, 32, 2)


def test_alg_2_tie_goes_to_series_order() -> None:
    series = [
        full(0.2),
        plateau(0, 1, range(10, 15)),
        plateau(0, 1, range(-60, -55)),
        full(0, **{"90": 1.0}),
    ]
    g = best_global(series)
    assert (g.series_index, g.local.theta_deg, g.local.half_window) == (1, 12, 2)


def test_alg_3_worst_single_minimum() -> None:
    series = [full(0.5), full(0.5, m30=0.0), full(0.25), full(0.5)]
    g = worst_global(series)
    assert (g.series_index, g.local.theta_deg, g.local.value, g.local.half_window) == (1, -30, 0, 0)


def test_alg_3_tie_goes_to_larger_half_window() -> None:
    # The printed Alg. 3 would keep the first (h=0) candidate; the intent takes h=2.
    series = [full(1, **{"7": 0.0}), full(1), plateau(1, 0, range(100, 105)), full(1)]
    g = worst_global(series)
    assert (g.series_index, g.local.theta_deg, g.local.half_window) == (2, 102, 2)


def test_alg_3_tie_goes_to_series_order() -> None:
    series = [full(0.5), full(1, m50=0), full(1, **{"60": 0}), full(0.5)]
    g = worst_global(series)
    assert (g.series_index, g.local.theta_deg) == (1, -50)


def test_alg_2_needs_a_series() -> None:
    with pytest.raises(InputError, match=r"Alg\. 2/3"):
        best_global([])
