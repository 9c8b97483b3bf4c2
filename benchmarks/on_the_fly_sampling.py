"""Adaptive against exhaustive on-the-fly predictions at the same budget: which picks the
better state for a new object? (docs/architecture.md, "Operation", `[operation] sampling`)

    PYTHONPATH=src .venv/bin/python benchmarks/on_the_fly_sampling.py [--objects o1,o5,...]

Per object, on a warm pool of two workers: the Experiment Manager's on-the-fly prediction
both ways, `--runs` runs per state (exhaustive: 28 × runs experiments; adaptive: at most as
many, `cps.dispatch.virtual_predictions(sampling="adaptive")`), each ranked as the TMS ranks
(its first state is the one an order would load), and a **reference** of the same object with
other seeds (`--reference-runs` runs per state, seed + 1000), independent of both picks. The
figure: the reference's success share of each pick (the true share estimated without the
pick's own runs), per object and averaged, the paired difference adaptive − exhaustive with a
bootstrap 95 % interval (better / worse / undecided), the regret of each against the
reference's best state, the experiments each used and their seconds.
"""

from __future__ import annotations

import argparse
import sys
import time

import numpy as np

OBJECTS = "o1,o5,o9,o12,o14,o18,o23,o28,o32,o36"
BOOTSTRAP = 4000


def shares(preds) -> dict[tuple, float]:
    return {(p.face, p.conveyor, p.theta_deg): p.share for p in preds}


def main() -> int:
    from transfertwin.cps.dispatch import virtual_predictions
    from transfertwin.study.experiment import WarmPool

    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--objects", default=OBJECTS)
    ap.add_argument("--runs", type=int, default=4, help="runs per state (the floor's default)")
    ap.add_argument("--reference-runs", type=int, default=12)
    ap.add_argument("--seed", type=int, default=0)
    args = ap.parse_args()
    objects = [o for o in args.objects.split(",") if o]
    rows = []
    with WarmPool(2) as pool:
        for obj in objects:
            row = {"object": obj}
            for how in ("exhaustive", "adaptive"):
                t0 = time.monotonic()
                preds = virtual_predictions(obj, args.runs, args.seed, executor=pool,
                                            sampling=how)  # fmt: skip
                row[f"{how}_s"] = time.monotonic() - t0
                row[f"{how}_runs"] = sum(p.n for p in preds)
                best = preds[0]
                row[f"{how}_pick"] = (best.face, best.conveyor, best.theta_deg)
                row[f"{how}_said"] = f"{best.k}/{best.n}"
            ref = shares(virtual_predictions(obj, args.reference_runs, args.seed + 1000,
                                             executor=pool))  # fmt: skip
            row["reference_best"] = max(ref.values())
            for how in ("exhaustive", "adaptive"):
                row[f"{how}_true"] = ref.get(row[f"{how}_pick"], float("nan"))
            rows.append(row)
            print(f"{obj:<4} exhaustive {'/'.join(map(str, row['exhaustive_pick'])):<20} "
                  f"{row['exhaustive_said']:>5} -> ref {row['exhaustive_true']:.2f} "
                  f"({row['exhaustive_runs']} runs, {row['exhaustive_s']:.1f} s)  adaptive "
                  f"{'/'.join(map(str, row['adaptive_pick'])):<20} {row['adaptive_said']:>5} -> "
                  f"ref {row['adaptive_true']:.2f} ({row['adaptive_runs']} runs, "
                  f"{row['adaptive_s']:.1f} s)  reference best {row['reference_best']:.2f}",
                  flush=True)  # fmt: skip
    ex = np.array([r["exhaustive_true"] for r in rows])
    ad = np.array([r["adaptive_true"] for r in rows])
    best = np.array([r["reference_best"] for r in rows])
    d = ad - ex
    rng = np.random.default_rng(args.seed)
    boot = [float(np.nanmean(d[rng.integers(0, len(d), len(d))])) for _ in range(BOOTSTRAP)]
    lo, hi = np.percentile(boot, [2.5, 97.5])
    verdict = "adaptive better" if lo > 0 else "adaptive worse" if hi < 0 else "undecided"
    print(f"\n{len(rows)} objects, {args.runs} runs per state, reference "
          f"{args.reference_runs} runs per state (other seeds):")
    print(f"  reference share of the pick: exhaustive {np.nanmean(ex):.3f}, adaptive "
          f"{np.nanmean(ad):.3f}; adaptive - exhaustive {np.nanmean(d):+.3f} "
          f"[{lo:+.3f}, {hi:+.3f}] (bootstrap 95 %): {verdict}")
    print(f"  regret against the reference's best: exhaustive {np.nanmean(best - ex):.3f}, "
          f"adaptive {np.nanmean(best - ad):.3f}")
    n_ex = np.mean([r["exhaustive_runs"] for r in rows])
    n_ad = np.mean([r["adaptive_runs"] for r in rows])
    print(f"  experiments (valid runs): exhaustive {n_ex:.0f}, adaptive {n_ad:.0f} per object; "
          f"seconds "
          f"exhaustive {np.median([r['exhaustive_s'] for r in rows]):.1f}, adaptive "
          f"{np.median([r['adaptive_s'] for r in rows]):.1f} (median)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
