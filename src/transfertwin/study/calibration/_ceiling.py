"""The data's own noise: near-repeats of a real experiment and the ceiling they put on any
predictor.

No two real rows share a state, but rows of the same object, face and conveyor whose yaw
differs by at most 5° (circular) are *near-repeats*. If the two rows of such a pair share
one success probability q (θ carrying no signal within 5°), then

- P(the pair disagrees) = 2 E[q (1 - q)], so the Brier score of an oracle that knows every
  row's q is E[q (1 - q)] = disagreement / 2, without further assumptions;
- the distribution of q over rows is fitted as a Beta distribution by the method of moments
  (mean = the success share of the pairs' rows, E[q²] = the share of pairs where both
  succeed; an exact fit of the beta-binomial of n = 2), and the oracle's F0.5 is the best
  expected F0.5 over thresholds t of 'success iff q >= t' under that Beta.

The interval resamples whole cells (object, face, conveyor) with their pairs (scipy's
percentile bootstrap), since a row can belong to several pairs.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import asdict, dataclass

import numpy as np

from transfertwin._errors import InputError

__all__ = ["NoiseCeiling", "near_repeat_pairs", "noise_ceiling", "oracle_scores"]

_GRID = np.linspace(0.002, 0.998, 250)


def near_repeat_pairs(
    rows: Sequence[Mapping[str, object]], max_dtheta_deg: float = 5.0
) -> np.ndarray:
    """Index pairs (m, 2), i < j, of rows with the same object, face and conveyor whose yaw
    differs by at most `max_dtheta_deg` (circular)."""
    key = np.array([f"{r['object_id']}|{r['face']}|{r['conveyor']}" for r in rows])
    theta = np.array([float(r["theta_deg"]) for r in rows])
    pairs = []
    for k in np.unique(key):
        idx = np.flatnonzero(key == k)
        d = np.abs((theta[idx][:, None] - theta[idx][None, :] + 180.0) % 360.0 - 180.0)
        i, j = np.nonzero(np.triu(d <= max_dtheta_deg, k=1))
        pairs += zip(idx[i].tolist(), idx[j].tolist(), strict=True)
    pairs.sort()
    return np.array(pairs, dtype=int).reshape(-1, 2)


def oracle_scores(mean: float, second: float) -> dict[str, float]:
    """Scores of the oracle under q ~ Beta with E[q] = `mean`, E[q²] = `second`: 'f05' (best
    expected F0.5 over thresholds), 'accuracy' (E max(q, 1 - q)), 'brier' (E q(1 - q)) and
    the Beta's 'alpha', 'beta' (inf when q does not vary, 0 when it is 0 or 1)."""
    from scipy.stats import beta as beta_dist

    mean = float(np.clip(mean, 0.0, 1.0))
    var = second - mean**2
    brier = float(max(mean - second, 0.0))
    if var <= 1e-12 or mean in (0.0, 1.0):  # q constant: always one answer
        f = 1.25 * mean / (1.25 * mean + 1 - mean) if mean > 0 else 0.0
        return {"f05": f, "accuracy": max(mean, 1 - mean), "brier": mean * (1 - mean),
                "alpha": float("inf"), "beta": float("inf")}  # fmt: skip
    if var >= mean * (1 - mean) - 1e-12:  # q is 0 or 1: the oracle is never wrong
        return {"f05": 1.0, "accuracy": 1.0, "brier": 0.0, "alpha": 0.0, "beta": 0.0}
    total = mean * (1 - mean) / var - 1
    a, b = mean * total, (1 - mean) * total
    above = beta_dist.sf(_GRID, a, b)  # P(q >= t)
    tp = mean * beta_dist.sf(_GRID, a + 1, b)  # E[q 1{q >= t}]
    fp, fn = above - tp, mean - tp
    f = 1.25 * tp / (1.25 * tp + 0.25 * fn + fp)
    acc = (1 - mean) * beta_dist.cdf(0.5, a, b + 1) + mean * beta_dist.sf(0.5, a + 1, b)
    return {
        "f05": float(max(f.max(), 1.25 * mean / (1.25 * mean + 1 - mean))),
        "accuracy": float(acc),
        "brier": brier,
        "alpha": float(a),
        "beta": float(b),
    }


@dataclass(frozen=True)
class NoiseCeiling:
    """The near-repeat estimate of the best any predictor can do on these rows.

    Attributes:
        pairs: Number of near-repeat pairs; rows: rows in at least one pair; cells: cells
            (object, face, conveyor) with a pair.
        disagreement: Share of pairs whose outcomes differ, with its 95 % interval.
        f05, accuracy, brier: The oracle's scores (`oracle_scores`), each with a 95 %
            interval (cell bootstrap); brier is disagreement / 2.
    """

    pairs: int
    rows: int
    cells: int
    max_dtheta_deg: float
    disagreement: float
    disagreement_ci: tuple[float, float]
    f05: float
    f05_ci: tuple[float, float]
    accuracy: float
    accuracy_ci: tuple[float, float]
    brier: float
    brier_ci: tuple[float, float]

    def to_dict(self) -> dict[str, object]:
        """Plain values for JSON."""
        return asdict(self)


def _moments(y: np.ndarray, pairs: np.ndarray) -> tuple[float, float, float]:
    a, b = y[pairs[:, 0]], y[pairs[:, 1]]
    return float(np.mean(a != b)), float(np.mean((a + b) / 2)), float(np.mean(a * b))


def noise_ceiling(
    rows: Sequence[Mapping[str, object]],
    *,
    max_dtheta_deg: float = 5.0,
    n_resamples: int = 2000,
    seed: int = 0,
) -> NoiseCeiling:
    """Near-repeat disagreement and the oracle's F0.5, accuracy and Brier score, with
    cell-bootstrap 95 % intervals. InputError without any near-repeat pair."""
    from scipy.stats import bootstrap

    y = np.array([int(r["success"]) for r in rows], dtype=float)
    pairs = near_repeat_pairs(rows, max_dtheta_deg)
    if len(pairs) < 2:
        raise InputError(f"fewer than 2 near-repeat pairs (|dtheta| <= {max_dtheta_deg} deg)")
    cell = np.array([f"{r['object_id']}|{r['face']}|{r['conveyor']}" for r in rows])
    cells, pair_cell = np.unique(cell[pairs[:, 0]], return_inverse=True)

    by_cell = [pairs[pair_cell == c] for c in range(len(cells))]

    def stats(which: np.ndarray) -> np.ndarray:
        chosen = np.concatenate([by_cell[c] for c in which.astype(int)])
        d, m, s = _moments(y, chosen)
        o = oracle_scores(m, s)
        return np.array([d, o["f05"], o["accuracy"], o["brier"]])

    point = stats(np.arange(len(cells)))
    res = bootstrap((np.arange(len(cells)),), stats, vectorized=False, paired=False,
                    n_resamples=n_resamples, method="percentile", confidence_level=0.95,
                    rng=np.random.default_rng(seed))  # fmt: skip
    lo, hi = res.confidence_interval.low, res.confidence_interval.high
    ci = [(float(lo[i]), float(hi[i])) for i in range(4)]
    return NoiseCeiling(len(pairs), len(np.unique(pairs)), len(cells), float(max_dtheta_deg),
                        float(point[0]), ci[0], float(point[1]), ci[1], float(point[2]), ci[2],
                        float(point[3]), ci[3])  # fmt: skip
