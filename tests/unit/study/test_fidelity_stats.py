"""The statistics of the fidelity headline (issue 29): rate tables, the near-repeat ceiling,
paired row-bootstrap intervals and the vectorised threshold, each on rows whose answer is
known."""

from __future__ import annotations

import numpy as np
import pytest

from transfertwin._errors import InputError
from transfertwin.study.calibration import (
    ConfusionMatrix,
    best_threshold,
    brier_of,
    f05_of,
    near_repeat_pairs,
    noise_ceiling,
    oracle_scores,
    paired_interval,
    rate_table,
    score_interval,
    shrunk_rate_table,
)


def _brute_threshold(p: np.ndarray, y: np.ndarray) -> float:
    best_t, best_f = 1.0, -1.0
    for t in np.unique(np.clip(p, 1e-6, 1.0)):
        f = ConfusionMatrix.from_predictions(p >= t, y.astype(bool)).f05
        if f > best_f + 1e-12:
            best_t, best_f = float(t), f
    return best_t


def test_vectorised_threshold_equals_the_brute_force_search() -> None:
    rng = np.random.default_rng(3)
    for i in range(400):
        n = int(rng.integers(1, 30))
        p = rng.random(n) if i % 2 else np.round(rng.random(n) * 4) / 4  # ties and 0/1
        y = rng.integers(0, 2, n)
        assert best_threshold(p, y) == _brute_threshold(p, y)


def test_rate_table_uses_training_rows_only_and_the_base_rate_for_unseen_cells() -> None:
    keys = np.array(["a", "a", "a", "b", "b", "c"])
    y = np.array([1, 1, 0, 0, 0, 1])
    train = np.array([0, 1, 3, 4])  # a: 2/2, b: 0/2; row 2 and cell c unseen
    p = rate_table(keys, y, train)
    assert p.tolist() == [1.0, 1.0, 1.0, 0.0, 0.0, 0.5]


def test_shrinkage_is_strong_for_noise_cells_and_weak_for_real_differences() -> None:
    rng = np.random.default_rng(0)
    parents = np.repeat(["P"], 400)
    keys = np.repeat([f"c{i}" for i in range(8)], 50)
    train = np.arange(400)
    # cells that differ only by chance: the rates of one coin -> shrink to the parent
    y_noise = (rng.random(400) < 0.6).astype(int)
    p_noise, m_noise = shrunk_rate_table(keys, parents, y_noise, train)
    # cells that really differ (0.1 vs 0.9) -> keep their own rates
    truth = np.repeat([0.1, 0.9] * 4, 50)
    y_real = (rng.random(400) < truth).astype(int)
    p_real, m_real = shrunk_rate_table(keys, parents, y_real, train)
    assert m_noise > 10 * m_real
    assert np.ptp(p_noise) < 0.5 * np.ptp(rate_table(keys, y_noise, train))
    assert np.max(np.abs(p_real - truth)) < 0.12
    # a cell without training rows gets its parent's rate
    p_unseen, _ = shrunk_rate_table(keys, parents, y_real, np.arange(350))
    assert p_unseen[-1] == pytest.approx(y_real[:350].mean())


def _row(obj: str, face: str, conveyor: str, theta: float, success: int) -> dict[str, object]:
    return {"object_id": obj, "face": face, "conveyor": conveyor, "theta_deg": theta,
            "success": success}  # fmt: skip


def test_near_repeats_need_the_same_cell_and_a_circular_yaw_within_5_degrees() -> None:
    rows = [_row("o1", "front", "left", 179, 1), _row("o1", "front", "left", -178, 0),
            _row("o1", "front", "right", 179, 1), _row("o1", "back", "left", 179, 1),
            _row("o1", "front", "left", 170, 1), _row("o1", "front", "left", 174, 1)]  # fmt: skip
    assert near_repeat_pairs(rows).tolist() == [[0, 1], [0, 5], [4, 5]]


def test_oracle_scores_at_the_extremes_and_the_brier_floor() -> None:
    assert oracle_scores(0.6, 0.6)["f05"] == 1.0  # q is 0 or 1: never wrong
    constant = oracle_scores(0.6, 0.36)  # q = 0.6 everywhere: always success
    assert constant["f05"] == pytest.approx(1.25 * 0.6 / (1.25 * 0.6 + 0.4))
    mid = oracle_scores(0.6, 0.45)
    assert mid["brier"] == pytest.approx(0.6 - 0.45)
    assert constant["f05"] < mid["f05"] < 1.0


def test_noise_ceiling_recovers_a_known_beta_oracle() -> None:
    rng = np.random.default_rng(1)
    a, b = 2.0, 1.0  # q ~ Beta(2, 1): E q = 2/3, E q^2 = 1/2
    rows = []
    for cell in range(600):  # one near-repeat pair per cell, sharing q
        q = rng.beta(a, b)
        for theta in (0.0, 3.0):
            rows.append(_row(f"o{cell}", "front", "left", theta, int(rng.random() < q)))
    c = noise_ceiling(rows, n_resamples=200, seed=0)
    truth = oracle_scores(2 / 3, 0.5)
    assert c.pairs == 600 and c.cells == 600
    assert c.disagreement == pytest.approx(2 * (2 / 3 - 0.5), abs=0.04)
    assert c.f05 == pytest.approx(truth["f05"], abs=0.02)
    assert c.brier == pytest.approx(c.disagreement / 2)
    assert c.f05_ci[0] <= truth["f05"] <= c.f05_ci[1]
    with pytest.raises(InputError, match="near-repeat"):
        noise_ceiling([*rows[:2], _row("x", "back", "both", 90.0, 1)], n_resamples=10)


def test_bootstrap_scores_match_confusion_counts_under_weights() -> None:
    y = np.array([1, 1, 0, 0, 1])
    bits = np.array([[1, 0, 1, 0, 1]])
    w = np.array([[1, 1, 1, 1, 1], [2, 0, 0, 1, 0]], dtype=float)
    f = f05_of(bits, y, w)
    assert f[0] == pytest.approx(ConfusionMatrix.from_predictions(bits[0], y).f05)
    assert f[1] == 1.0  # row 0 twice (TP), row 3 (TN)
    p = np.array([[0.9, 0.2, 0.5, 0.0, 1.0]])
    assert brier_of(p, y, w)[1] == pytest.approx((2 * 0.01 + 0.0) / 3)


def test_paired_interval_is_zero_for_equal_predictors_and_excludes_zero_for_a_real_gap() -> None:
    rng = np.random.default_rng(2)
    y = rng.integers(0, 2, 300)
    noisy = np.where(rng.random((3, 300)) < 0.8, y, 1 - y).astype(bool)
    always = np.ones((3, 300), dtype=bool)
    d, ci = paired_interval("f05", noisy, noisy, y, n_resamples=200)
    assert d == 0.0 and ci == (0.0, 0.0)
    d, ci = paired_interval("f05", noisy, always, y, n_resamples=200)
    assert d > 0.1 and ci[0] > 0
    lo, hi = score_interval("brier", np.full((1, 300), 0.5), y, n_resamples=200)
    assert lo == hi == pytest.approx(0.25)
    clusters = np.repeat(np.arange(30), 10)
    lo, hi = score_interval("f05", noisy, y, clusters=clusters, n_resamples=200)
    assert lo < f05_of(noisy, y, np.ones((1, 300)))[0] < hi
