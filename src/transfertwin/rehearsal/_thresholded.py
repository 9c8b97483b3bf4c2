"""The rehearsal's held-out figures as `calibrate evaluate` states them: one decision per row
and the Brier score of the probabilities (issue 29).

`f05_before`/`f05_after` are the mean over R runs of each run's F0.5 (an unthresholded
score). Here each held-out row gets the twin's probability P = the share of its R runs that
succeed, and one decision, success iff P >= 0.5 (the majority of the runs; the oracle
benchmark thresholds the plant's own reruns the same way). Scored: F0.5 of the decisions
and the Brier score of P, before and after calibration, with row-bootstrap 95 % intervals
and the paired after − before difference (`transfertwin.study.calibration.paired_interval`).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from transfertwin.study.calibration import brier_of, f05_of, paired_interval, score_interval

__all__ = ["majority_scores"]


def majority_scores(
    p_before: Sequence[float],
    p_after: Sequence[float],
    actual: Sequence[int],
    *,
    n_resamples: int = 2000,
    seed: int = 0,
) -> dict[str, object]:
    """F0.5 of 'success iff P >= 0.5' and the Brier score of P, before and after, on the
    held-out rows: values, 95 % intervals and the paired differences after − before."""
    y = np.asarray(actual, dtype=int)
    pb = np.asarray(p_before, dtype=float)[None, :]
    pa = np.asarray(p_after, dtype=float)[None, :]
    ones = np.ones((1, len(y)))
    out: dict[str, object] = {"threshold": 0.5}
    for name, p in (("before", pb), ("after", pa)):
        bits = p >= 0.5
        out[f"f05_{name}"] = float(f05_of(bits, y, ones)[0])
        out[f"f05_{name}_ci"] = score_interval("f05", bits, y, n_resamples=n_resamples,
                                               seed=seed)  # fmt: skip
        out[f"brier_{name}"] = float(brier_of(p, y, ones)[0])
        out[f"brier_{name}_ci"] = score_interval("brier", p, y, n_resamples=n_resamples,
                                                 seed=seed)  # fmt: skip
    d, ci = paired_interval("f05", pa >= 0.5, pb >= 0.5, y, n_resamples=n_resamples, seed=seed)
    out["f05_delta"], out["f05_delta_ci"] = d, ci
    d, ci = paired_interval("brier", pa, pb, y, n_resamples=n_resamples, seed=seed)
    out["brier_delta"], out["brier_delta_ci"] = d, ci
    return out
