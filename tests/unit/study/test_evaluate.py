"""Honest evaluation (issue: fidelity): fold hygiene, thresholds, baselines on the real rows."""

from __future__ import annotations

import numpy as np
import pytest

from transfertwin.data import calibration_csv_path
from transfertwin.store import read_results
from transfertwin.study.calibration import (
    best_threshold,
    choose_candidates,
    cv_splits,
    evaluate_predictions,
    fold_predictions,
    score,
    shrink,
)


@pytest.fixture(scope="module")
def real_rows() -> list[dict[str, object]]:
    return read_results(calibration_csv_path())


def test_constant_predictor_threshold_says_success_and_scores_the_base_rate(real_rows) -> None:
    y = np.array([int(r["success"]) for r in real_rows])
    p = np.full(len(y), y.mean())
    s = score(p, y, best_threshold(p, y))
    # 128 of 191 real successes: precision 128/191, recall 1 -> F0.5 = 0.7175 (issue text)
    assert (int(y.sum()), len(y)) == (128, 191)
    assert s.recall == 1.0 and s.f05 == pytest.approx(0.7175, abs=5e-5)
    assert s.brier == pytest.approx(np.mean((y.mean() - y) ** 2))


def test_best_threshold_separates_perfect_probabilities() -> None:
    y = np.array([0, 0, 1, 1, 1])
    p = np.array([0.1, 0.3, 0.6, 0.7, 0.9])
    t = best_threshold(p, y)
    assert 0.3 < t <= 0.6 and score(p, y, t).f05 == 1.0


def test_candidate_choice_looks_only_at_the_given_rows() -> None:
    y = np.array([1, 1, 0, 0, 1, 0])
    objects = np.array(["a"] * 6)
    good_on_first_half = np.array([1, 1, 0, 1, 0, 1], dtype=float)
    good_on_second_half = np.array([0, 0, 1, 0, 1, 0], dtype=float)
    cands = {"a": np.vstack([good_on_first_half, good_on_second_half])}
    assert choose_candidates(cands, objects, y, np.array([0, 1, 2])) == {"a": 0}
    assert choose_candidates(cands, objects, y, np.array([3, 4, 5])) == {"a": 1}


def test_fold_hygiene_no_choice_depends_on_the_test_fold() -> None:
    rng = np.random.default_rng(3)
    n = 60
    y = rng.integers(0, 2, n)
    objects = np.array(["a", "b"] * 30)
    cands = {o: rng.random((4, n)) for o in ("a", "b")}
    splits = cv_splits(y, folds=3, repeats=2, seed=1)
    for train, test in splits:
        poisoned = y.copy()
        poisoned[test] = 1 - poisoned[test]  # anything a leaky choice would react to
        ((_, p1, t1, c1),) = fold_predictions(cands, objects, y, [(train, test)])
        ((_, p2, t2, c2),) = fold_predictions(cands, objects, poisoned, [(train, test)])
        assert (c1, t1) == (c2, t2) and np.array_equal(p1, p2)
        assert set(train).isdisjoint(test)


def test_shrinkage_bounds_the_log_loss_of_hard_shares_and_keeps_their_order() -> None:
    rng = np.random.default_rng(5)
    n = 200
    p = rng.choice([0.0, 0.5, 1.0], n)
    y = (rng.random(n) < 0.15 + 0.7 * p).astype(int)  # informative but noisy
    train = np.arange(0, n, 2)
    q = shrink(p, y, train)
    assert score(q[train], y[train], 0.5).log_loss < score(p[train], y[train], 0.5).log_loss
    assert q.min() > 0 and q.max() < 1
    assert np.array_equal(np.argsort(q, kind="stable"), np.argsort(p, kind="stable"))
    assert best_threshold(q, y) > 0 and score(q, y, best_threshold(q, y)).f05 == pytest.approx(
        score(p, y, best_threshold(p, y)).f05
    )
    poisoned = y.copy()
    poisoned[1::2] = 1 - poisoned[1::2]  # the rows outside `train` do not matter
    assert np.array_equal(shrink(p, poisoned, train), q)
    perfect = np.array([0.0, 1.0] * 20)
    assert np.array_equal(shrink(perfect, perfect.astype(int), np.arange(40)), perfect)


def test_regularisation_keeps_the_prior_when_the_gain_is_small() -> None:
    y = np.array([1, 0, 1, 0])
    objects = np.array(["a"] * 4)
    prior = np.array([0.6, 0.4, 0.6, 0.4])
    slightly_better = np.array([0.65, 0.35, 0.65, 0.35])
    cands = {"a": np.vstack([prior, slightly_better])}
    rows = np.arange(4)
    assert choose_candidates(cands, objects, y, rows, penalty=0.0) == {"a": 1}
    assert choose_candidates(cands, objects, y, rows, penalty=0.1) == {"a": 0}


def test_evaluation_reports_every_figure_beside_the_baselines(real_rows) -> None:
    y = np.array([int(r["success"]) for r in real_rows])
    objects = np.array([str(r["object_id"]) for r in real_rows])
    # an oracle-ish candidate per object (its real share) and an uninformative one
    cands = {}
    for o in set(objects):
        share = np.where(objects == o, y[objects == o].mean(), 0.5)
        cands[str(o)] = np.vstack([np.full(len(y), 0.2), share])
    ev = evaluate_predictions(real_rows, cands, folds=5, repeats=2, seed=0)
    for key in ("base_rate", "logistic_in_sample", "logistic_cv", "twin_in_sample", "twin_cv"):
        assert {"f05", "precision", "recall", "brier"} <= set(ev.figures[key])
    assert ev.figures["base_rate"]["f05"] == pytest.approx(0.7175, abs=5e-5)
    assert ev.figures["logistic_cv"]["f05"] > ev.figures["base_rate"]["f05"]
    assert set(ev.per_object) == {"o1", "o18", "o23", "o32"}
    assert sum(v["n"] for v in ev.per_object.values()) == 191
    assert ev.chosen == {o: 1 for o in cands}
