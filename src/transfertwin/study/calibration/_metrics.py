"""Binary classification metrics of virtual against real results (App. A.2, Table 6.4).

A calibration run compares the virtual outcome (the *prediction*) of each real
experiment with its real outcome (the *actual condition*), Table A.2:

- TP: predicted success, real success; FP: predicted success, real failure;
- FN: predicted failure, real success; TN: predicted failure, real failure.

Precision (Eq. A.1), recall (Eq. A.2), accuracy (Eq. A.3) and F_β (Eq. A.4 with
β = 0.5) follow from the counts. **Zero denominators:** every ratio whose
denominator is 0 is defined as 0, as scikit-learn does with ``zero_division=0``:
precision = 0 when TP + FP = 0, recall = 0 when TP + FN = 0, accuracy = 0 for an
empty matrix, and F_β = 0 when TP + FP + FN = 0. F_β is computed from the counts,
(1 + β²)·TP / ((1 + β²)·TP + β²·FN + FP), which equals Eq. A.4 wherever Eq. A.4
is defined and gives 0 where precision = recall = 0.

Repeated runs (Table 6.4, A.6, A.7) are summarised by `summarize_runs` as mean
± standard deviation over runs; the standard deviation is the sample one,
``ddof=1`` by default (the study does not state its choice).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import asdict, dataclass
from numbers import Integral, Real
from typing import Any

import numpy as np

from transfertwin._errors import InputError

__all__ = ["RUN_METRICS", "ConfusionMatrix", "summarize_runs"]

#: Quantities `summarize_runs` reports per run, in the column order of Table 6.4.
RUN_METRICS: tuple[str, ...] = (
    "pp", "pn", "fp", "fn", "tp", "tn", "accuracy", "precision", "recall", "f05",
)  # fmt: skip


def _ratio(num: float, den: float) -> float:
    """num / den, or 0.0 when den = 0 (scikit-learn's ``zero_division=0``)."""
    return num / den if den else 0.0


def _binary(values: object, name: str) -> np.ndarray:
    """Flatten ``values`` into a bool array; InputError unless every entry is 0 or 1."""
    arr = np.asarray(values)
    if arr.dtype == bool:
        return arr.ravel()
    if arr.dtype.kind not in "iuf" or not np.all(np.isin(arr, (0, 1))):
        raise InputError(f"App. A.2: {name} outcomes must be 0/1 or booleans")
    return arr.ravel().astype(bool)


@dataclass(frozen=True)
class ConfusionMatrix:
    """Counts of Table A.2: virtual predictions against real outcomes.

    Attributes:
        tp: Predicted success, real success.
        fp: Predicted success, real failure.
        fn: Predicted failure, real success.
        tn: Predicted failure, real failure.
    """

    tp: int
    fp: int
    fn: int
    tn: int

    def __post_init__(self) -> None:
        for name in ("tp", "fp", "fn", "tn"):
            value = getattr(self, name)
            if isinstance(value, (bool, np.bool_)) or not isinstance(value, Integral) or value < 0:
                raise InputError(f"Table A.2: {name} must be a non-negative integer, got {value!r}")
            object.__setattr__(self, name, int(value))

    @classmethod
    def from_predictions(cls, predicted: object, actual: object) -> ConfusionMatrix:
        """Count a run from paired binary outcomes.

        Args:
            predicted: Virtual outcomes, shape ``(N,)``, 0/1 or bool.
            actual: Real outcomes of the same experiments, shape ``(N,)``.

        Raises:
            InputError: On non-binary values, different lengths or N = 0.
        """
        pred, act = _binary(predicted, "predicted"), _binary(actual, "actual")
        if pred.shape != act.shape:
            raise InputError(
                f"App. A.2: {pred.size} predicted and {act.size} actual outcomes differ in length"
            )
        if pred.size == 0:
            raise InputError("App. A.2: no outcomes to compare")
        return cls(
            int(np.sum(pred & act)),
            int(np.sum(pred & ~act)),
            int(np.sum(~pred & act)),
            int(np.sum(~pred & ~act)),
        )

    @property
    def pp(self) -> int:
        """Predicted positives PP = TP + FP."""
        return self.tp + self.fp

    @property
    def pn(self) -> int:
        """Predicted negatives PN = FN + TN."""
        return self.fn + self.tn

    @property
    def total(self) -> int:
        """Population P + N."""
        return self.tp + self.fp + self.fn + self.tn

    @property
    def precision(self) -> float:
        """TP / (TP + FP) (Eq. A.1); 0 when TP + FP = 0."""
        return _ratio(self.tp, self.tp + self.fp)

    @property
    def recall(self) -> float:
        """TP / (TP + FN) (Eq. A.2); 0 when TP + FN = 0."""
        return _ratio(self.tp, self.tp + self.fn)

    @property
    def accuracy(self) -> float:
        """(TP + TN) / (P + N) (Eq. A.3); 0 for an empty matrix."""
        return _ratio(self.tp + self.tn, self.total)

    def f_beta(self, beta: float) -> float:
        """F_β score (Eq. A.4 for general β); 0 when TP + FP + FN = 0.

        Args:
            beta: Weight of recall relative to precision, finite and > 0.

        Raises:
            InputError: If beta is not a finite positive number.
        """
        if isinstance(beta, bool) or not isinstance(beta, Real) or not 0 < beta < math.inf:
            raise InputError(f"beta must be a finite positive number, got {beta!r} (Eq. A.4)")
        b2 = float(beta) ** 2
        return _ratio((1 + b2) * self.tp, (1 + b2) * self.tp + b2 * self.fn + self.fp)

    @property
    def f05(self) -> float:
        """F_0.5 (Eq. A.4), the study's calibration score."""
        return self.f_beta(0.5)

    def metric(self, name: str) -> float:
        """One of `RUN_METRICS` by name."""
        if name not in RUN_METRICS:
            raise InputError(f"Table 6.4: unknown metric {name!r}; use {', '.join(RUN_METRICS)}")
        return float(getattr(self, name))

    def to_dict(self) -> dict[str, int]:
        """``{"tp": …, "fp": …, "fn": …, "tn": …}``; inverse of `from_dict`."""
        return asdict(self)

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> ConfusionMatrix:
        """Rebuild a matrix written by `to_dict`."""
        return cls(**data)


def summarize_runs(runs: Sequence[ConfusionMatrix], *, ddof: int = 1) -> dict[str, Any]:
    """Per-run values, mean and standard deviation of `RUN_METRICS` (Table 6.4).

    Args:
        runs: One confusion matrix per calibration run.
        ddof: Delta degrees of freedom of the standard deviation; 1 (default)
            gives the sample standard deviation, 0 the population one. With
            fewer than ``ddof + 1`` runs the standard deviation is NaN.

    Returns:
        ``{"n_runs": R, "ddof": ddof, "metrics": {name: {"values": [R floats],
        "mean": float, "std": float}}}`` with names in `RUN_METRICS` order.

    Raises:
        InputError: If ``runs`` is empty, holds a non-`ConfusionMatrix` or ddof < 0.
    """
    runs = list(runs)
    if not runs:
        raise InputError("Table 6.4: no runs to summarise")
    if not all(isinstance(run, ConfusionMatrix) for run in runs):
        raise InputError("Table 6.4: every run must be a ConfusionMatrix")
    if isinstance(ddof, bool) or not isinstance(ddof, Integral) or ddof < 0:
        raise InputError(f"Table 6.4: ddof must be a non-negative integer, got {ddof!r}")
    metrics: dict[str, dict[str, Any]] = {}
    for name in RUN_METRICS:
        values = np.array([run.metric(name) for run in runs], dtype=float)
        std = float(np.std(values, ddof=ddof)) if len(values) > ddof else math.nan
        metrics[name] = {"values": values.tolist(), "mean": float(values.mean()), "std": std}
    return {"n_runs": len(runs), "ddof": int(ddof), "metrics": metrics}
