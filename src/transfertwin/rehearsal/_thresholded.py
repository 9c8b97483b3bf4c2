"""The rehearsal's held-out figures as `calibrate evaluate` states them: one decision per row
and the Brier score of the probabilities.

`f05_before`/`f05_after` are the mean over R runs of each run's F0.5 (an unthresholded
score). Here each held-out row gets the twin's probability P = the share of its R runs that
succeed, and one decision, success iff P >= t. As `calibrate evaluate` does, t is chosen on
the training rows (`training_threshold`: the twin's P on them, `best_threshold`), one t for
the twin before and one after calibration; with R = 1, P is 0 or 1 and every t in (0, 1]
gives the same decisions, so t = 0.5 without replaying the training rows. Scored: F0.5 of
the decisions and the Brier score of P, before and after calibration, with row-bootstrap
95 % intervals and the paired after − before difference
(`transfertwin.study.calibration.paired_interval`).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from transfertwin.study.calibration import (
    best_threshold,
    brier_of,
    f05_of,
    paired_interval,
    score_interval,
)

__all__ = ["majority_scores", "training_threshold"]


def training_threshold(p_train: Sequence[float], y_train: Sequence[int]) -> float:
    """The decision threshold t chosen on the training rows: the one that maximises F0.5 of
    'success iff P >= t' there (`best_threshold`; ties to the lowest t)."""
    p, y = np.asarray(p_train, dtype=float), np.asarray(y_train, dtype=int)
    if p.shape != y.shape or p.ndim != 1:
        raise ValueError(f"training_threshold: {p.shape} probabilities for {y.shape} outcomes")
    return float(best_threshold(p, y)) if p.size else 0.5


def majority_scores(
    p_before: Sequence[float],
    p_after: Sequence[float],
    actual: Sequence[int],
    *,
    n_resamples: int = 2000,
    seed: int = 0,
    thresholds: tuple[float, float] = (0.5, 0.5),
    threshold_source: str = "0.5",
) -> dict[str, object]:
    """F0.5 of 'success iff P >= t' and the Brier score of P, before and after, on the
    held-out rows: values, 95 % intervals and the paired differences after − before.
    `thresholds`: t of the twin before and after calibration (chosen on the training rows,
    `training_threshold`); `threshold_source` says where they come from."""
    y = np.asarray(actual, dtype=int)
    pb = np.asarray(p_before, dtype=float)[None, :]
    pa = np.asarray(p_after, dtype=float)[None, :]
    ones = np.ones((1, len(y)))
    tb, ta = (float(t) for t in thresholds)
    out: dict[str, object] = {"threshold_before": tb, "threshold_after": ta,
                              "threshold_source": threshold_source}  # fmt: skip
    for name, p, t in (("before", pb, tb), ("after", pa, ta)):
        bits = p >= t
        out[f"f05_{name}"] = float(f05_of(bits, y, ones)[0])
        out[f"f05_{name}_ci"] = score_interval("f05", bits, y, n_resamples=n_resamples,
                                               seed=seed)  # fmt: skip
        out[f"brier_{name}"] = float(brier_of(p, y, ones)[0])
        out[f"brier_{name}_ci"] = score_interval("brier", p, y, n_resamples=n_resamples,
                                                 seed=seed)  # fmt: skip
    d, ci = paired_interval("f05", pa >= ta, pb >= tb, y, n_resamples=n_resamples, seed=seed)
    out["f05_delta"], out["f05_delta_ci"] = d, ci
    d, ci = paired_interval("brier", pa, pb, y, n_resamples=n_resamples, seed=seed)
    out["brier_delta"], out["brier_delta_ci"] = d, ci
    return out
