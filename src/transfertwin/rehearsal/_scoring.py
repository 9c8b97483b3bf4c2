"""How the rehearsal scores the twin on the held-out plant experiments: F0.5 as the study
defines it for Table 6.4 (Appendix A.2: the mean over the R replay runs of each run's F0.5),
the always-'success' predictor's F0.5 beside it, and paired percentile-bootstrap intervals of
both and of their differences over the held-out rows. `_rehearse` runs the experiments and
calls these; `_thresholded` scores one thresholded decision per row instead.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import numpy as np

from transfertwin._errors import InputError
from transfertwin.study.calibration import CalibrationResult

__all__ = [
    "BOOTSTRAP_REPLICATES",
    "base_rate_f05",
    "f05_intervals",
    "held_out_scores",
    "run_predictions",
]


#: Resamples of the held-out rows behind the F0.5 intervals (percentile bootstrap, seed 0).
BOOTSTRAP_REPLICATES = 2000


def held_out_scores(result: CalibrationResult) -> dict[str, float]:
    """F0.5, precision, recall and accuracy of a replay (each the mean over its runs) and
    the Brier score of its probabilities (the share of runs that succeed per row)."""
    p, y = result.probabilities(), np.asarray(result.actual)
    out = {m: result.metric(m) for m in ("f05", "precision", "recall", "accuracy")}
    out["brier"] = float(np.mean((p - y) ** 2))
    return out


def base_rate_f05(y: Sequence[int]) -> float:
    """F0.5 of the predictor that always says 'success' (precision = base rate, recall 1)."""
    p = sum(y) / len(y)
    return 0.0 if p == 0 else 1.25 * p / (0.25 * p + 1)


def _f05_rows(pred: np.ndarray, act: np.ndarray) -> np.ndarray:
    """F0.5 per resample: `pred` and `act` (B, n) bool (0 where nothing is predicted)."""
    tp = (pred & act).sum(1)
    fp = (pred & ~act).sum(1)
    fn = (~pred & act).sum(1)
    den = 1.25 * tp + 0.25 * fn + fp
    return np.divide(1.25 * tp, den, out=np.zeros(len(den)), where=den > 0)


def f05_intervals(
    predictions: Mapping[str, np.ndarray],
    actual: Sequence[int],
    *,
    replicates: int = BOOTSTRAP_REPLICATES,
    seed: int = 0,
    alpha: float = 0.05,
    differences: Sequence[tuple[str, str]] = (),
) -> dict[str, list[float]]:
    """Paired percentile-bootstrap intervals of F0.5 on the held-out rows.

    Each resample draws the held-out rows with replacement once and scores every predictor
    on the same rows (the mean over runs of each run's F0.5, as ``f05_*``), and the
    always-success predictor ('base_rate'). With 'before' and 'after' it adds their paired
    difference 'after_minus_before'; each pair (a, b) of `differences` adds 'a_minus_b'
    (e.g. an oracle's F0.5 minus the twin's: the gap, paired row by row).

    Args:
        predictions: Name → virtual outcomes per run and held-out row, (R, n) of 0/1.
        actual: The plant's outcomes (n,).
        replicates: Resamples B.
        seed: Seed of the resampling.
        alpha: 1 - confidence level.

    Returns:
        Name → [low, high].
    """
    act = np.asarray(actual, dtype=bool)
    if act.ndim != 1 or act.size == 0:
        raise InputError("f05_intervals: need at least one held-out row")
    unknown = sorted({n for pair in differences for n in pair} - set(predictions))
    if unknown:
        raise InputError(f"f05_intervals: differences name no predictor: {', '.join(unknown)}")
    idx = np.random.default_rng([seed, 0x424F4F54]).integers(0, act.size, (replicates, act.size))
    a = act[idx]
    stats: dict[str, np.ndarray] = {"base_rate": _f05_rows(np.ones_like(a), a)}
    for name, pred in predictions.items():
        pred = np.asarray(pred, dtype=bool)
        if pred.ndim != 2 or pred.shape[1] != act.size:
            raise InputError(f"f05_intervals: {name} needs (runs, {act.size}) predictions")
        stats[name] = np.mean([_f05_rows(run[idx], a) for run in pred], axis=0)
    if "before" in stats and "after" in stats:
        stats["after_minus_before"] = stats["after"] - stats["before"]
    for a_name, b_name in differences:
        stats[f"{a_name}_minus_{b_name}"] = stats[a_name] - stats[b_name]
    q = (alpha / 2, 1 - alpha / 2)
    return {k: [float(v) for v in np.quantile(x, q)] for k, x in stats.items()}


def run_predictions(result: CalibrationResult) -> np.ndarray:
    """The replay's virtual outcomes, (R, n) of 0/1: one row per run, one column per row."""
    return np.array([r.predicted for r in result.runs], dtype=int)
