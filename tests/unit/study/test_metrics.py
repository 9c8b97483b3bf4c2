"""Confusion matrix, precision/recall/accuracy/F_β (App. A.2) and run summaries (Table 6.4).

Expected values are derived by hand from the counts, or come from scikit-learn
(an independent implementation, used only here) with ``zero_division=0``.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from sklearn.metrics import accuracy_score, fbeta_score, precision_score, recall_score

from transfertwin._errors import InputError
from transfertwin.study.calibration._metrics import RUN_METRICS, ConfusionMatrix, summarize_runs


def test_table_a2_counts_from_predictions_by_hand() -> None:
    predicted = [1, 1, 1, 0, 0, 0, 1, 0, 1]
    actual = [1, 0, 1, 1, 0, 0, 1, 0, 0]
    cm = ConfusionMatrix.from_predictions(predicted, actual)
    assert cm == ConfusionMatrix(tp=3, fp=2, fn=1, tn=3)
    assert (cm.pp, cm.pn, cm.total) == (5, 4, 9)
    assert cm.precision == pytest.approx(3 / 5)
    assert cm.recall == pytest.approx(3 / 4)
    assert cm.accuracy == pytest.approx(6 / 9)


def test_eq_a4_f05_by_hand_on_table_6_4_sized_counts() -> None:
    cm = ConfusionMatrix(tp=105, fp=18, fn=29, tn=47)
    # (1 + 0.25) * 105 / ((1 + 0.25) * 105 + 0.25 * 29 + 18) = 131.25 / 156.5
    assert cm.f05 == pytest.approx(131.25 / 156.5, rel=1e-12)
    p, r = 105 / 123, 105 / 134
    assert cm.f05 == pytest.approx(1.25 * p * r / (0.25 * p + r), rel=1e-12)  # Eq. A.4 as printed
    assert cm.f_beta(1.0) == pytest.approx(2 * p * r / (p + r), rel=1e-12)
    assert cm.accuracy == pytest.approx(152 / 199)


@pytest.mark.parametrize(
    ("cm", "precision", "recall", "accuracy", "f05"),
    [
        (ConfusionMatrix(0, 0, 0, 5), 0.0, 0.0, 1.0, 0.0),  # nothing positive at all
        (ConfusionMatrix(0, 0, 3, 2), 0.0, 0.0, 0.4, 0.0),  # never predicts success
        (ConfusionMatrix(0, 4, 0, 1), 0.0, 0.0, 0.2, 0.0),  # no real success
        (ConfusionMatrix(0, 0, 0, 0), 0.0, 0.0, 0.0, 0.0),  # empty matrix
        (ConfusionMatrix(2, 0, 0, 0), 1.0, 1.0, 1.0, 1.0),
    ],
)
def test_app_a2_zero_denominators_give_zero(
    cm: ConfusionMatrix, precision: float, recall: float, accuracy: float, f05: float
) -> None:
    assert (cm.precision, cm.recall, cm.accuracy, cm.f05) == (precision, recall, accuracy, f05)


def _cases() -> list[tuple[np.ndarray, np.ndarray]]:
    rng = np.random.default_rng(20240605)
    cases = []
    for n, p_pred, p_act in [(10, 0.5, 0.5), (50, 0.8, 0.6), (200, 0.62, 0.67), (7, 0.1, 0.9)]:
        for _ in range(5):
            cases.append((rng.random(n) < p_pred, rng.random(n) < p_act))
    ones, zeros = np.ones(6, dtype=bool), np.zeros(6, dtype=bool)
    mixed = np.array([1, 0, 1, 0, 1, 0], dtype=bool)
    cases += [(ones, ones), (zeros, zeros), (ones, zeros), (zeros, ones), (zeros, mixed),
              (mixed, zeros), (mixed, ~mixed), (mixed, mixed)]  # fmt: skip
    return cases


@pytest.mark.parametrize(("predicted", "actual"), _cases())
def test_eq_a1_to_a4_match_scikit_learn(predicted: np.ndarray, actual: np.ndarray) -> None:
    cm = ConfusionMatrix.from_predictions(predicted.astype(int), actual.astype(int))
    y_true, y_pred = actual.astype(int), predicted.astype(int)
    opts = {"zero_division": 0, "labels": [0, 1], "pos_label": 1}
    assert cm.f05 == pytest.approx(fbeta_score(y_true, y_pred, beta=0.5, **opts), abs=1e-12)
    for beta in (0.25, 1.0, 2.0):
        assert cm.f_beta(beta) == pytest.approx(
            fbeta_score(y_true, y_pred, beta=beta, **opts), abs=1e-12
        )
    assert cm.precision == pytest.approx(precision_score(y_true, y_pred, **opts), abs=1e-12)
    assert cm.recall == pytest.approx(recall_score(y_true, y_pred, **opts), abs=1e-12)
    assert cm.accuracy == pytest.approx(accuracy_score(y_true, y_pred), abs=1e-12)


def test_app_a2_accepts_bools_and_float_zero_one() -> None:
    a = ConfusionMatrix.from_predictions([True, False], np.array([1.0, 0.0]))
    assert a == ConfusionMatrix(1, 0, 0, 1)


@pytest.mark.parametrize(
    ("predicted", "actual"),
    [([1, 2], [1, 0]), ([1, float("nan")], [1, 0]), (["1", "0"], [1, 0]), ([1, 0, 1], [1, 0]),
     ([], [])],
)  # fmt: skip
def test_app_a2_rejects_bad_outcomes(predicted: list, actual: list) -> None:
    with pytest.raises(InputError, match=r"App\. A\.2"):
        ConfusionMatrix.from_predictions(predicted, actual)


@pytest.mark.parametrize("counts", [(-1, 0, 0, 0), (1.5, 0, 0, 0), (True, 0, 0, 0)])
def test_table_a2_rejects_bad_counts(counts: tuple) -> None:
    with pytest.raises(InputError, match=r"Table A\.2"):
        ConfusionMatrix(*counts)


@pytest.mark.parametrize("beta", [0, -1, math.inf, math.nan, True])
def test_eq_a4_rejects_bad_beta(beta: float) -> None:
    with pytest.raises(InputError, match=r"Eq\. A\.4"):
        ConfusionMatrix(1, 1, 1, 1).f_beta(beta)


def test_confusion_matrix_round_trips_through_a_dict() -> None:
    cm = ConfusionMatrix(4, 3, 2, 1)
    assert cm.to_dict() == {"tp": 4, "fp": 3, "fn": 2, "tn": 1}
    assert ConfusionMatrix.from_dict(cm.to_dict()) == cm


def test_table_6_4_summarize_runs_mean_and_sample_std_by_hand() -> None:
    runs = [ConfusionMatrix(3, 1, 1, 3), ConfusionMatrix(2, 0, 2, 4)]
    summary = summarize_runs(runs)
    assert summary["n_runs"] == 2 and summary["ddof"] == 1
    assert list(summary["metrics"]) == list(RUN_METRICS)
    f05 = summary["metrics"]["f05"]
    # run 1: 1.25*3 / (3.75 + 0.25 + 1) = 0.75; run 2: 2.5 / (2.5 + 0.5) = 5/6
    assert f05["values"] == pytest.approx([0.75, 5 / 6])
    assert f05["mean"] == pytest.approx((0.75 + 5 / 6) / 2)
    assert f05["std"] == pytest.approx((5 / 6 - 0.75) / math.sqrt(2))  # ddof = 1
    tp = summary["metrics"]["tp"]
    assert (tp["values"], tp["mean"], tp["std"]) == ([3.0, 2.0], 2.5, pytest.approx(0.5**0.5))
    assert summary["metrics"]["pp"]["values"] == [4.0, 2.0]
    pop = summarize_runs(runs, ddof=0)["metrics"]["f05"]["std"]
    assert pop == pytest.approx((5 / 6 - 0.75) / 2)


def test_table_6_4_one_run_has_no_sample_std() -> None:
    metrics = summarize_runs([ConfusionMatrix(1, 0, 0, 1)])["metrics"]
    assert metrics["accuracy"]["mean"] == 1.0
    assert math.isnan(metrics["accuracy"]["std"])
    assert summarize_runs([ConfusionMatrix(1, 0, 0, 1)], ddof=0)["metrics"]["f05"]["std"] == 0.0


@pytest.mark.parametrize(
    ("runs", "ddof"), [([], 1), ([(1, 0, 0, 1)], 1), ([ConfusionMatrix(1, 0, 0, 1)], -1)]
)
def test_table_6_4_summarize_runs_rejects_bad_input(runs: list, ddof: int) -> None:
    with pytest.raises(InputError, match=r"Table 6\.4"):
        summarize_runs(runs, ddof=ddof)
