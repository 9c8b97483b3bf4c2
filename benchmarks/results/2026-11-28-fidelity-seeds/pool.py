"""Pool the small rehearsals of several plant seeds per plant kind (12 held-out rows each).

One decision per held-out row (``p >= t``, t as each rehearsal recorded it), the oracle's
majority from ``oracle_rows.csv``; paired percentile-bootstrap intervals over the pooled rows
(`f05_intervals`, 2000 resamples, seed 0); the operations' orders pooled with a Newcombe
interval. Run from the repository root (seeds 2,3,4 unless given, e.g. 1,2,3,4):

    .venv/bin/python benchmarks/results/2026-11-28-fidelity-seeds/pool.py [SEEDS]
"""

from __future__ import annotations

import csv
import json
import sys
from pathlib import Path

import numpy as np
from statsmodels.stats.proportion import confint_proportions_2indep

from transfertwin.rehearsal import f05_intervals

HERE = Path(__file__).resolve().parent


def _f05(pred: np.ndarray, y: np.ndarray) -> float:
    tp, fp, fn = (pred & y).sum(), (pred & ~y).sum(), (~pred & y).sum()
    return 0.0 if tp == 0 else float(1.25 * tp / (1.25 * tp + 0.25 * fn + fp))


def pool(kind: str, seeds: tuple[int, ...]) -> None:
    y, before, after, majority, pb, pa = [], [], [], [], [], []
    k_twin = n_twin = k_rand = n_rand = 0
    for s in seeds:
        d = HERE / f"small-seed{s}-{kind}"
        doc = json.loads((d / "rehearsal.json").read_text())
        t = doc["thresholded"]
        tb, ta = t.get("threshold_before", 0.5), t.get("threshold_after", 0.5)
        maj = {int(r["experiment_id"]): int(r["majority"]) for r in csv.DictReader((d / "oracle_rows.csv").open())}
        for r in csv.DictReader((d / "held_out_predictions.csv").open()):
            y.append(int(r["success"]))
            pb.append(float(r["p_before"]))
            pa.append(float(r["p_after"]))
            before.append(int(float(r["p_before"]) >= tb))
            after.append(int(float(r["p_after"]) >= ta))
            majority.append(maj[int(r["experiment_id"])])
        ops = doc["operations"]
        k_twin, n_twin = k_twin + ops["twin"]["k"], n_twin + ops["twin"]["n"]
        k_rand, n_rand = k_rand + ops["random"]["k"], n_rand + ops["random"]["n"]
    ya = np.array(y, bool)
    preds = {"before": np.array([before]), "after": np.array([after]), "majority": np.array([majority])}
    ci = f05_intervals(preds, y, differences=[("majority", "after")])
    f = {k: _f05(v[0].astype(bool), ya) for k, v in preds.items()}
    rng = np.random.default_rng(0)
    idx = rng.integers(0, len(y), (2000, len(y)))
    yb, pbb, pab = ya[idx], np.array(pb)[idx], np.array(pa)[idx]
    bb, ba = ((pbb - yb) ** 2).mean(1), ((pab - yb) ** 2).mean(1)
    q = lambda x: np.quantile(x, [0.025, 0.975])  # noqa: E731
    brier_b, brier_a = float(((np.array(pb) - ya) ** 2).mean()), float(((np.array(pa) - ya) ** 2).mean())
    lo, hi = confint_proportions_2indep(k_twin, n_twin, k_rand, n_rand, method="newcomb")
    print(f"{kind}, seeds {','.join(map(str, seeds))}: {len(y)} held-out rows, {sum(y)} successes")
    print(f"  always-success {_f05(np.ones(len(y), bool), ya):.3f} [{ci['base_rate'][0]:.2f}, {ci['base_rate'][1]:.2f}]")
    print(f"  F0.5 before {f['before']:.3f} [{ci['before'][0]:.2f}, {ci['before'][1]:.2f}], after {f['after']:.3f} "
          f"[{ci['after'][0]:.2f}, {ci['after'][1]:.2f}], after - before {f['after'] - f['before']:+.3f} "
          f"[{ci['after_minus_before'][0]:+.2f}, {ci['after_minus_before'][1]:+.2f}]")
    print(f"  Brier before {brier_b:.3f}, after {brier_a:.3f}, after - before {brier_a - brier_b:+.3f} "
          f"[{q(ba - bb)[0]:+.2f}, {q(ba - bb)[1]:+.2f}]")
    print(f"  oracle majority {f['majority']:.3f} [{ci['majority'][0]:.2f}, {ci['majority'][1]:.2f}], gap "
          f"{f['majority'] - f['after']:+.3f} [{ci['majority_minus_after'][0]:+.3f}, {ci['majority_minus_after'][1]:+.3f}]")
    print(f"  operations: twin {k_twin}/{n_twin} vs random {k_rand}/{n_rand}, difference "
          f"{k_twin / n_twin - k_rand / n_rand:+.2f} [{lo:.2f}, {hi:.2f}] (Newcombe)")


if __name__ == "__main__":
    seeds = tuple(int(s) for s in sys.argv[1].split(",")) if len(sys.argv) > 1 else (2, 3, 4)
    for kind in ("in-class", "mismatch"):
        pool(kind, seeds)
