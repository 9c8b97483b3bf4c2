"""Rehearsal on an emulated plant: the issue-12 targets beside their baselines, in one run.

Runs `transfertwin.rehearsal.rehearse` on a small configuration (default: plant seed 1,
o3 and o7, K = 40 calibration experiments, R = 2, 10 validation runs per best/worst state,
90° grid, every counter-measure ablated once, 20 orders per operating policy) and prints:

- F0.5 on held-out plant experiments before and after calibration beside the always-success
  predictor (the baseline; ratio printed). Target: after >= 0.90.
- Objects whose best/worst state differs significantly between twin and plant (Newcombe),
  scaled to 37 objects for the target: <= 5 of 37 best states.
- Per ablated counter-measure, the same figures without it (the gap it closes).
- Operations (Sec. 7.2): success rate and completed operations per hour with the twin's
  recommendation against random placement (the baseline), Wilson / Newcombe / bootstrap
  95 % intervals. Target: success significantly above random.

With several K (``-k 25,50,100``) it runs one rehearsal per K and prints the curve.

    python benchmarks/rehearsal.py [--plant-seed 1] [--plant-kind in-class|mismatch|bullet]
        [--mismatch-off PART,...]
        [--objects o3,o7] [-k 40] [--runs 2]
        [--validation-runs 10] [--test-experiments 0] [--workers 2] [--tune-trials 0]
        [--ablate mass,stability,compliance] [--operations 20] [--out DIR]

Full configuration (hours on 2 cores): `--objects o1,...,o37 -k 200 --runs 4
--validation-runs 20 --theta-step 30 --tune-trials 20 --operations 200`.
"""

from __future__ import annotations

import argparse
import tempfile
import time
from pathlib import Path

from transfertwin.rehearsal import (
    COUNTER_MEASURES,
    RehearsalConfig,
    curve_document,
    parse_object_list,
    rehearse,
)


def _gap(doc: dict, n: int, label: str) -> None:
    scaled = doc["significant_best"] / n * 37
    print(
        f"{label:<22} F0.5 after {doc['f05_after']:.3f}; significant best "
        f"{doc['significant_best']}/{n} (~{scaled:.1f}/37), worst {doc['significant_worst']}/{n}"
    )


def _report(doc: dict, cfg: RehearsalConfig) -> None:
    base = doc["f05_base_rate"]
    n = len(cfg.objects)
    print(f"held-out plant experiments: {doc['held_out']} (training {doc['training']})")
    print(f"F0.5 always-success (baseline): {base:.3f}")
    lo, hi = doc["f05_base_rate_ci"]
    print(f"  95 % bootstrap interval over the held-out rows [{lo:.3f}, {hi:.3f}]")
    for key in ("f05_before", "f05_after"):
        ratio = doc[key] / base if base else float("nan")
        lo, hi = doc[f"{key}_ci"]
        print(f"{key}: {doc[key]:.3f} [{lo:.3f}, {hi:.3f}]  ({ratio:.2f}x baseline)")
    lo, hi = doc["f05_delta_ci"]
    print(f"after - before: {doc['f05_after'] - doc['f05_before']:+.3f} [{lo:+.3f}, {hi:+.3f}] "
          "(paired bootstrap; an interval holding 0: no measurable change)")  # fmt: skip
    print("target F0.5 after >= 0.90:", "met" if doc["f05_after"] >= 0.90 else "NOT met")
    t = doc.get("thresholded")
    if t:
        print(f"one decision per row (success iff P >= t; t before "
              f"{t.get('threshold_before', 0.5):.3g}, after {t.get('threshold_after', 0.5):.3g}: "
              f"{t.get('threshold_source', '0.5')}), as calibrate evaluate scores: F0.5 "
              f"before {t['f05_before']:.3f} [{t['f05_before_ci'][0]:.2f}, "
              f"{t['f05_before_ci'][1]:.2f}], after {t['f05_after']:.3f} "
              f"[{t['f05_after_ci'][0]:.2f}, {t['f05_after_ci'][1]:.2f}], after - before "
              f"{t['f05_delta']:+.3f} [{t['f05_delta_ci'][0]:+.2f}, {t['f05_delta_ci'][1]:+.2f}]; "
              f"Brier before {t['brier_before']:.3f}, after {t['brier_after']:.3f}, after - "
              f"before {t['brier_delta']:+.3f} [{t['brier_delta_ci'][0]:+.2f}, "
              f"{t['brier_delta_ci'][1]:+.2f}]")  # fmt: skip
    print(f"significant best: {doc['significant_best']}/{n} {doc['significant_best_objects']}")
    print(f"significant worst: {doc['significant_worst']}/{n} {doc['significant_worst_objects']}")
    scaled = doc["significant_best"] / n * 37
    print(
        f"target <= 5/37 significant best: {'met' if scaled <= 5 else 'NOT met'} "
        f"({scaled:.1f}/37 at this share; the study's twins: 12/37)"
    )
    if doc["ablations"]:
        print("counter-measures (gap with all on, then each switched off):")
        _gap(doc, n, "  all on")
        for m, ab in doc["ablations"].items():
            _gap(ab, n, f"  without {m}")
            print(
                f"{'':<24}delta F0.5 {ab['delta_f05_after']:+.3f}, significant best "
                f"{ab['delta_significant_best']:+d}, worst {ab['delta_significant_worst']:+d}; "
                f"unstable runs {ab['virtual_unstable']}, re-run {ab['virtual_rerun']} "
                f"(all on: {doc['virtual_unstable']}, {doc['virtual_rerun']})"
            )
    ops = doc["operations"]
    if ops:
        print(f"operations: {ops['orders']} orders per policy, twin docks at {ops['station']}")
        for policy, label in (("random", "random placement (baseline)"), ("twin", "twin")):
            p = ops[policy]
            print(
                f"  {label:<27} success {p['k']}/{p['n']} = {p['success_rate']:.2f} "
                f"[{p['success_low']:.2f}, {p['success_high']:.2f}] (Wilson); "
                f"{p['ops_per_hour']:.1f} completed ops/h "
                f"[{p['ops_per_hour_low']:.1f}, {p['ops_per_hour_high']:.1f}] (bootstrap)"
            )
        print(
            f"  success difference {ops['success_diff']:+.2f} "
            f"[{ops['success_diff_low']:.2f}, {ops['success_diff_high']:.2f}] (Newcombe); "
            f"ops/h ratio {ops['ops_per_hour_ratio']:.2f}x random "
            f"[{ops.get('ops_per_hour_ratio_low', float('nan')):.2f}, "
            f"{ops.get('ops_per_hour_ratio_high', float('nan')):.2f}]"
        )
        print(
            "target success significantly above random:",
            "met" if ops["success_above_random"] else "NOT met",
        )
    print(
        f"plant experiments {doc['plant_experiments']}, virtual {doc['virtual_experiments']}, "
        f"{doc['seconds']} s on {cfg.workers} workers"
    )


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--plant-seed", type=int, default=1)
    ap.add_argument("--plant-kind", default="in-class", choices=("in-class", "mismatch", "bullet"),
                    help="mismatch: a plant outside the twin's model class; bullet: the "
                    "in-class plant in PyBullet")  # fmt: skip
    ap.add_argument("--mismatch-off", default="",
                    help="mismatch parts switched off, e.g. sag (a rehearsal per ablated part)")
    ap.add_argument("--objects", default="o3,o7")
    ap.add_argument("-k", "--calibration-experiments", default="40")
    ap.add_argument("--runs", type=int, default=2)
    ap.add_argument("--validation-runs", type=int, default=10)
    ap.add_argument("--theta-step", type=int, default=90)
    ap.add_argument("--test-experiments", type=int, default=0, help="separate held-out set H")
    ap.add_argument("--tune-trials", type=int, default=0)
    ap.add_argument("--ablate", default=",".join(COUNTER_MEASURES), help="'' for none")
    ap.add_argument("--operations", type=int, default=20)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--out", type=Path, default=None)
    args = ap.parse_args()
    ks = [int(k) for k in args.calibration_experiments.split(",")]
    out = args.out or Path(tempfile.mkdtemp(prefix="rehearsal-"))
    docs = []
    for k in ks:
        cfg = RehearsalConfig(
            plant_seed=args.plant_seed, objects=parse_object_list(args.objects),
            calibration_experiments=k, runs=args.runs, validation_runs=args.validation_runs,
            theta_step=args.theta_step, test_experiments=args.test_experiments,
            tune_trials=args.tune_trials, seed=args.seed,
            workers=args.workers, ablate=(args.ablate,) if args.ablate else (),
            operations=args.operations, plant_kind=args.plant_kind,
            mismatch_off=tuple(p for p in args.mismatch_off.split(",") if p),
        )  # fmt: skip
        where = out if len(ks) == 1 else out / f"K{k}"
        t0 = time.perf_counter()
        print(f"== K = {k}, plant {args.plant_kind} (seed {args.plant_seed})")
        doc = rehearse(
            cfg, where, on_stage=lambda s, t0=t0: print(f"[{time.perf_counter() - t0:6.0f} s] {s}")
        )
        _report(doc, cfg)
        docs.append(doc)
    if len(ks) > 1:
        print("experiments-needed curve (K: F0.5 before -> after, significant best/worst):")
        for p in curve_document(docs)["curve"]:
            print(
                f"  K={p['calibration_experiments']}: {p['f05_before']:.3f} -> "
                f"{p['f05_after']:.3f} [{p['f05_after_ci'][0]:.2f}, {p['f05_after_ci'][1]:.2f}] "
                f"(always-success {p['f05_base_rate']:.3f}, held-out {p['held_out']}); "
                f"{p['significant_best']}/{p['significant_worst']}"
            )
    print(f"-> {out}")


if __name__ == "__main__":
    main()
