"""Row-bootstrap intervals of held-out scores and of paired differences between predictors.

Held-out predictions come as arrays (S, n): one row per CV seed (each a full out-of-fold
pass over the n real rows). A score is the mean over seeds of F0.5 (of the 0/1 decisions)
or of the Brier score (of the probabilities). A bootstrap resample draws n rows (or whole
clusters of rows) with replacement and recomputes the seed-averaged score on it — the same
rows for both predictors of a difference (paired). The interval is scipy's percentile
bootstrap.
"""

from __future__ import annotations

import numpy as np

__all__ = ["brier_of", "f05_of", "paired_interval", "score_interval"]


def _weights(draws: np.ndarray, clusters: np.ndarray | None, n: int) -> np.ndarray:
    """(B, n) how often each row is in each resample; `draws` (B, m) drawn unit indices."""
    draws = np.atleast_2d(draws).astype(int)
    units = n if clusters is None else int(clusters.max()) + 1
    b = draws.shape[0]
    flat = (draws + units * np.arange(b)[:, None]).ravel()
    w = np.bincount(flat, minlength=b * units).reshape(b, units).astype(float)
    return w if clusters is None else w[:, clusters]


def f05_of(bits: np.ndarray, y: np.ndarray, w: np.ndarray) -> np.ndarray:
    """Seed-averaged F0.5 (B,) of decisions `bits` (S, n) against `y` (n,) under row
    weights `w` (B, n); 0 where a resample has no TP, FP or FN."""
    bits, y = np.asarray(bits, dtype=float), np.asarray(y, dtype=float)
    tp = w @ (bits * y).T
    fp = w @ (bits * (1 - y)).T
    fn = w @ ((1 - bits) * y).T
    den = 1.25 * tp + 0.25 * fn + fp
    f = np.divide(1.25 * tp, den, out=np.zeros_like(tp), where=den > 0)
    return f.mean(axis=1)


def brier_of(p: np.ndarray, y: np.ndarray, w: np.ndarray) -> np.ndarray:
    """Seed-averaged Brier score (B,) of probabilities `p` (S, n) under row weights `w`."""
    sq = (np.asarray(p, dtype=float) - np.asarray(y, dtype=float)) ** 2
    return (w @ sq.T / w.sum(axis=1, keepdims=True)).mean(axis=1)


def _interval(stat, n: int, clusters: np.ndarray | None, n_resamples: int,
              seed: int) -> tuple[float, float]:  # fmt: skip
    from scipy.stats import bootstrap

    units = n if clusters is None else int(clusters.max()) + 1
    if units < 2:  # nothing to resample
        return float("nan"), float("nan")

    def statistic(draws: np.ndarray, axis: int = -1) -> np.ndarray:
        draws = np.moveaxis(np.asarray(draws), axis, -1)
        shape = draws.shape[:-1]
        out = stat(_weights(draws.reshape(-1, draws.shape[-1]), clusters, n))
        return out.reshape(shape)

    res = bootstrap((np.arange(units),), statistic, vectorized=True, n_resamples=n_resamples,
                    method="percentile", confidence_level=0.95, batch=500,
                    rng=np.random.default_rng(seed))  # fmt: skip
    return float(res.confidence_interval.low), float(res.confidence_interval.high)


def score_interval(
    kind: str, pred: np.ndarray, y: np.ndarray, *, clusters: np.ndarray | None = None,
    n_resamples: int = 2000, seed: int = 0,
) -> tuple[float, float]:  # fmt: skip
    """95 % interval of one predictor's seed-averaged 'f05' (pred = decisions) or 'brier'
    (pred = probabilities), resampling rows (or `clusters`, (n,) ints 0..c-1)."""
    fn = f05_of if kind == "f05" else brier_of
    pred = np.atleast_2d(pred)
    return _interval(lambda w: fn(pred, y, w), len(y), clusters, n_resamples, seed)


def paired_interval(
    kind: str, a: np.ndarray, b: np.ndarray, y: np.ndarray, *,
    clusters: np.ndarray | None = None, n_resamples: int = 2000, seed: int = 0,
) -> tuple[float, tuple[float, float]]:  # fmt: skip
    """The difference a − b of the seed-averaged 'f05' or 'brier' on all rows and its
    paired 95 % bootstrap interval (the same resampled rows for both)."""
    fn = f05_of if kind == "f05" else brier_of
    a, b = np.atleast_2d(a), np.atleast_2d(b)
    ones = np.ones((1, len(y)))
    diff = float(fn(a, y, ones)[0] - fn(b, y, ones)[0])
    ci = _interval(lambda w: fn(a, y, w) - fn(b, y, w), len(y), clusters, n_resamples, seed)
    return diff, ci
