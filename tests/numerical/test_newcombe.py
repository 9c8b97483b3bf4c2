"""Newcombe hybrid score interval for p₁ − p₂ (Sec. 6.7) against independent numbers.

Published values: Newcombe (1998), "Interval estimation for the difference between
independent proportions: comparison of eleven methods", Stat. Med. 17, Table II,
method 10 (score interval, no continuity correction), 95 %, four decimals, for the
paper's eight examples (a)–(h).

Note on example (c), 6/7 − 2/7: the published method-10 interval is
[0.0582, 0.8062]. The pair [0.0531, 0.8317] that circulated in the task brief is
not method 10 (nor method 11, with continuity correction: [-0.0290, 0.8423]); the
closed form below reproduces 0.0582/0.8062 independently of statsmodels. All
examples, (c) and (d) included, agree with statsmodels to the 4th decimal, so the
tolerance is half a unit in the last published digit (5e-5).

Second check: the closed form of method 10 written out here with scipy's normal
quantile (Wilson interval per proportion, combined by square-and-add), compared
over a grid of counts and two confidence levels.
"""

from __future__ import annotations

import math

import pytest
from scipy.stats import norm

from transfertwin._errors import InputError
from transfertwin.study.validation import NEWCOMBE_HYBRID_SCORE, newcombe_difference

NEWCOMBE_1998_TABLE_II_METHOD_10 = [
    # (k1, n1, k2, n2, low, high), examples (a)-(h)
    (56, 70, 48, 80, 0.0524, 0.3339),
    (9, 10, 3, 10, 0.1705, 0.8090),
    (6, 7, 2, 7, 0.0582, 0.8062),
    (5, 56, 0, 29, -0.0381, 0.1926),
    (0, 10, 0, 20, -0.1611, 0.2775),
    (0, 10, 0, 10, -0.2775, 0.2775),
    (10, 10, 0, 20, 0.6791, 1.0000),
    (10, 10, 0, 10, 0.6075, 1.0000),
]


@pytest.mark.parametrize(("k1", "n1", "k2", "n2", "low", "high"), NEWCOMBE_1998_TABLE_II_METHOD_10)
def test_sec_6_7_newcombe_1998_table_ii_method_10(
    k1: int, n1: int, k2: int, n2: int, low: float, high: float
) -> None:
    ci = newcombe_difference(k1, n1, k2, n2, alpha=0.05)
    assert ci.low == pytest.approx(low, abs=5e-5)
    assert ci.high == pytest.approx(high, abs=5e-5)
    assert ci.estimate == pytest.approx(k1 / n1 - k2 / n2)
    assert ci.method == NEWCOMBE_HYBRID_SCORE


def _wilson(k: int, n: int, z: float) -> tuple[float, float]:
    p = k / n
    centre = (2 * n * p + z * z) / (2 * (n + z * z))
    half = z * math.sqrt(z * z + 4 * n * p * (1 - p)) / (2 * (n + z * z))
    return centre - half, centre + half


def _square_and_add(k1: int, n1: int, k2: int, n2: int, alpha: float) -> tuple[float, float]:
    z = norm.ppf(1 - alpha / 2)
    (l1, u1), (l2, u2) = _wilson(k1, n1, z), _wilson(k2, n2, z)
    p1, p2 = k1 / n1, k2 / n2
    d = p1 - p2
    return d - math.hypot(p1 - l1, u2 - p2), d + math.hypot(u1 - p1, p2 - l2)


@pytest.mark.parametrize("alpha", [0.05, 0.1])
def test_sec_6_7_newcombe_matches_the_closed_form_on_a_grid(alpha: float) -> None:
    for n1, n2 in [(1, 1), (7, 7), (20, 50), (50, 20)]:
        for k1 in range(0, n1 + 1, max(1, n1 // 5)):
            for k2 in range(0, n2 + 1, max(1, n2 // 5)):
                ci = newcombe_difference(k1, n1, k2, n2, alpha)
                low, high = _square_and_add(k1, n1, k2, n2, alpha)
                assert ci.low == pytest.approx(low, abs=1e-9), (k1, n1, k2, n2)
                assert ci.high == pytest.approx(high, abs=1e-9), (k1, n1, k2, n2)


def test_sec_6_7_newcombe_swapping_the_sides_mirrors_the_interval() -> None:
    a, b = newcombe_difference(5, 56, 0, 29), newcombe_difference(0, 29, 5, 56)
    assert (a.low, a.high) == pytest.approx((-b.high, -b.low), abs=1e-12)


@pytest.mark.parametrize(
    ("args", "alpha"),
    [((1, 0, 1, 1), 0.05), ((1, 1, 0, 0), 0.05), ((3, 2, 1, 1), 0.05), ((1, 2, 1, 2), 1.5)],
)
def test_sec_6_7_newcombe_rejects_bad_counts_and_alpha(args: tuple, alpha: float) -> None:
    with pytest.raises(InputError):
        newcombe_difference(*args, alpha=alpha)
