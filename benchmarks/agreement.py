"""Full-size agreement check: the fast defaults against the 'reference' profile.

Runs the same experiments under both profiles and prints, per scene, the success shares
with their Clopper–Pearson 95 % intervals (they agree when each share lies in the other's
interval), the share of experiments with the same outcome, steps per experiment and exp/s.
Scenes: 'default' and failure-producing variants ('gap30': d_gap = 30 mm; 'mu0.15':
belt friction 0.15), so that agreement is not trivially "always success". Then the 191
real calibration rows are replayed under both profiles (`--calibration-runs`, 0 skips).

    PYTHONPATH=src .venv/bin/python benchmarks/agreement.py \
        [--objects o1,o18,o23,o32] [--theta-step 30] [--runs 4] [--scenes default,gap30] \
        [--set physics.pulley_facets=32 --set layout.pulley_radius_m=0.0125] \
        [--fast-set stall_mode=progress]

`--set` overrides apply to both sides, `--fast-set` to the fast side only (a lever on trial).
"""

from __future__ import annotations

import argparse

import numpy as np

from _engine import parse_sets
from transfertwin.data import calibration_csv_path
from transfertwin.sim import scene_profile
from transfertwin.store import read_results
from transfertwin.study import ResampledDockingErrors, StudyPlan
from transfertwin.study.calibration import calibrate
from transfertwin.study.validation import SideOutcome, compare_scenes
from transfertwin.web import bootstrap_f05

SCENES = {"default": {}, "gap30": {"gap_m": 0.03}, "mu0.15": {"mu": 0.15}}


def _calibration(runs: int, both: dict[str, object], fast: dict[str, object]) -> None:
    rows = read_results(calibration_csv_path())
    real = sum(int(r["success"]) for r in rows)
    print(f"\ncalibration replay: {len(rows)} real rows ({real} real successes) x {runs} runs")
    f05 = {}
    for name in ("fast", "reference"):
        extra = {**both, **fast} if name == "fast" else both
        res = calibrate(rows, runs=runs, scene=scene_profile(name, **extra))
        wins = sum(sum(r.predicted) for r in res.runs)
        n = len(rows) * runs
        side = SideOutcome(wins, n, sum(r.not_ok for r in res.runs), 0, 0.0, ())
        ci = side.interval
        low, high = bootstrap_f05(np.array([r.predicted for r in res.runs]),
                                  np.array(res.actual))  # fmt: skip
        f05[name] = (res.metric("f05"), low, high)
        print(f"  {name:<10} predicted success {wins}/{n} = {side.share:6.1%} "
              f"[{ci.low:.3f}, {ci.high:.3f}]  accuracy {res.metric('accuracy'):.3f}  "
              f"F0.5 {res.metric('f05'):.3f} [{low:.3f}, {high:.3f}]  "
              f"not ok {side.not_ok}")  # fmt: skip
    (f, fl, fh), (r, rl, rh) = f05["fast"], f05["reference"]
    same = rl <= f <= rh and fl <= r <= fh
    print(f"  F0.5 {'AGREE' if same else 'DIFFER'} (each inside the other's bootstrap interval)")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--objects", default="o1,o18,o23,o32")
    parser.add_argument("--theta-step", type=int, default=30)
    parser.add_argument("--runs", type=int, default=4)
    parser.add_argument("--scenes", default="default,gap30", help=",".join(SCENES))
    parser.add_argument("--calibration-runs", type=int, default=1)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                        help="scene override for both sides")  # fmt: skip
    parser.add_argument("--fast-set", action="append", default=[], metavar="KEY=VALUE",
                        help="scene override for the fast side only")  # fmt: skip
    args = parser.parse_args()
    both, fast_only = parse_sets(args.set), parse_sets(args.fast_set)
    objects = tuple(args.objects.split(","))
    plan = StudyPlan(objects, args.theta_step, args.runs, args.seed,
                     ResampledDockingErrors.from_csv())  # fmt: skip
    specs = [spec for _, spec in plan.specs({o: o for o in objects})]
    print(f"{len(objects)} objects x {len(plan.states())} states x {args.runs} runs "
          f"= {len(specs)} experiments per scene and profile")  # fmt: skip
    for label in args.scenes.split(","):
        extra = {**both, **SCENES[label]}
        a = compare_scenes(label, specs, scene_profile("fast", **extra, **fast_only),
                           scene_profile("reference", **extra))  # fmt: skip
        f, r = a.fast, a.reference
        print(a.line())
        print(f"{'':<14} steps/exp fast {f.steps / f.n:.0f} ref {r.steps / r.n:.0f}; "
              f"exp/s fast {f.rate:.2f} ref {r.rate:.2f} ({f.rate / r.rate:.2f}x); "
              f"not ok fast {f.not_ok} ref {r.not_ok}", flush=True)  # fmt: skip
    if args.calibration_runs:
        _calibration(args.calibration_runs, both, fast_only)


if __name__ == "__main__":
    main()
