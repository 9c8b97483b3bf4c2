"""Rehearsal on an emulated plant: F0.5 before/after calibration and significant differences.

Runs `transfertwin.rehearsal.rehearse` on a small configuration (default: plant seed 1,
o3 and o7, K = 40 calibration experiments, R = 2, 10 validation runs per best/worst state,
90° grid) and prints, in one run, the twin's held-out F0.5 before and after calibration
beside the always-success predictor (the baseline; ratio printed), and how many objects'
best/worst states differ significantly from the plant (Newcombe). Targets (issue 12,
for the full configuration): F0.5 after calibration >= 0.90 on held-out plant experiments;
<= 5 of 37 objects with a significantly different best state.

    python benchmarks/rehearsal.py [--plant-seed 1] [--objects o3,o7] [-k 40] [--runs 2]
        [--validation-runs 10] [--workers 2] [--tune-trials 0] [--out DIR]

Full configuration (hours on 2 cores): `--objects o1,...,o37 -k 200 --runs 4
--validation-runs 20 --theta-step 30 --tune-trials 20`.
"""

from __future__ import annotations

import argparse
import tempfile
import time
from pathlib import Path

from transfertwin.rehearsal import RehearsalConfig, parse_object_list, rehearse


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--plant-seed", type=int, default=1)
    ap.add_argument("--objects", default="o3,o7")
    ap.add_argument("-k", "--calibration-experiments", type=int, default=40)
    ap.add_argument("--runs", type=int, default=2)
    ap.add_argument("--validation-runs", type=int, default=10)
    ap.add_argument("--theta-step", type=int, default=90)
    ap.add_argument("--tune-trials", type=int, default=0)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--out", type=Path, default=None)
    args = ap.parse_args()
    cfg = RehearsalConfig(
        plant_seed=args.plant_seed, objects=parse_object_list(args.objects),
        calibration_experiments=args.calibration_experiments, runs=args.runs,
        validation_runs=args.validation_runs, theta_step=args.theta_step,
        tune_trials=args.tune_trials, seed=args.seed, workers=args.workers,
    )  # fmt: skip
    out = args.out or Path(tempfile.mkdtemp(prefix="rehearsal-"))
    t0 = time.perf_counter()
    doc = rehearse(cfg, out, on_stage=lambda s: print(f"[{time.perf_counter() - t0:6.0f} s] {s}"))
    base = doc["f05_base_rate"]
    n = len(cfg.objects)
    print(f"held-out plant experiments: {doc['held_out']} (training {doc['training']})")
    print(f"F0.5 always-success (baseline): {base:.3f}")
    for key in ("f05_before", "f05_after"):
        ratio = doc[key] / base if base else float("nan")
        print(f"{key}: {doc[key]:.3f}  ({ratio:.2f}x baseline)")
    print("target f05_after >= 0.90:", "met" if doc["f05_after"] >= 0.90 else "NOT met")
    print(f"significant best: {doc['significant_best']}/{n} {doc['significant_best_objects']}")
    print(f"significant worst: {doc['significant_worst']}/{n} {doc['significant_worst_objects']}")
    print(
        f"plant experiments {doc['plant_experiments']}, virtual {doc['virtual_experiments']}, "
        f"{doc['seconds']} s on {cfg.workers} workers -> {out / 'rehearsal.json'}"
    )


if __name__ == "__main__":
    main()
