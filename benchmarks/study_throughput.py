"""Study throughput, fast defaults against the 'reference' profile, in the same run.

For each profile the same plan (objects x states x runs, resampled real docking errors)
runs three ways:

- in-process loop: exp/s, physics steps per experiment and the overhead ratio = wall time
  over the time spent in `mj_step` for exactly these experiments (1.00 = no framework cost);
- `run_study` with 1 worker into a fresh SQLite store (adds the store and the runner);
- `run_study` with N worker processes (`--workers 0` skips it; keep it short on 2 cores).

    PYTHONPATH=src .venv/bin/python benchmarks/study_throughput.py \
        [--objects o1,o18] [--theta-step 45] [--runs 2] [--workers 2] [--profiles fast,reference] \
        [--set physics.pulley_facets=32 --set layout.pulley_radius_m=0.0125]

A profile is a built-in name or a profile TOML file (`transfertwin.study.load_profile`);
`--set KEY=VALUE` overrides are applied to every profile.
"""

from __future__ import annotations

import argparse
import tempfile
from pathlib import Path

from _engine import parse_sets, timed_experiments
from transfertwin.store import SQLiteResultStore
from transfertwin.study import ResampledDockingErrors, StudyPlan, load_profile, run_study


def _study_rate(plan: StudyPlan, workers: int, tmp: Path) -> float:
    with SQLiteResultStore(tmp / f"{plan.profile_name}-w{workers}.sqlite") as store:
        outcome = run_study(plan, store, workers=workers)
    return outcome.rate


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--objects", default="o1,o18")
    parser.add_argument("--theta-step", type=int, default=45)
    parser.add_argument("--runs", type=int, default=2)
    parser.add_argument("--workers", type=int, default=2, help="0 skips the pool run")
    parser.add_argument("--profiles", default="fast,reference", help="names or TOML files")
    parser.add_argument("--set", action="append", default=[], metavar="KEY=VALUE")
    args = parser.parse_args()
    extra = parse_sets(args.set)
    docking = ResampledDockingErrors.from_csv()
    objects = tuple(args.objects.split(","))
    rows = {}
    with tempfile.TemporaryDirectory() as tmp:
        for profile in args.profiles.split(","):
            name, scene = load_profile(profile)
            scene = scene.with_overrides(**extra) if extra else scene
            plan = StudyPlan(objects, args.theta_step, args.runs, 0, docking,
                             scene=scene, profile_name=name)  # fmt: skip
            specs = [spec for _, spec in plan.specs({o: o for o in objects})]
            timed = timed_experiments(specs)
            rate1 = _study_rate(plan, 1, Path(tmp))
            rate_n = _study_rate(plan, args.workers, Path(tmp)) if args.workers > 1 else None
            ok = sum(r.status == "ok" for r in timed.results)
            wins = sum(r.success == 1 for r in timed.results)
            rows[name] = (timed, rate1, rate_n, ok, wins)
            print(f"[{name}] {plan.n_experiments} experiments ({ok} ok, {wins} successes)",
                  flush=True)  # fmt: skip
    print(f"\n{'profile':<10} {'loop exp/s':>10} {'steps/exp':>9} {'engine exp/s':>12} "
          f"{'overhead':>8} {'study 1w':>9} {'study ' + str(args.workers) + 'w':>9}")  # fmt: skip
    for name, (timed, rate1, rate_n, _, _) in rows.items():
        engine_rate = len(timed.results) / timed.engine_s
        pool = f"{rate_n:9.2f}" if rate_n is not None else f"{'-':>9}"
        print(f"{name:<10} {timed.rate:10.2f} {timed.steps_per_experiment:9.0f} "
              f"{engine_rate:12.2f} {timed.overhead:8.3f} {rate1:9.2f} {pool}")  # fmt: skip
    if "fast" in rows and "reference" in rows:
        f, r = rows["fast"][0], rows["reference"][0]
        print(
            f"\nspeed-up fast/reference: {f.rate / r.rate:.2f}x (in-process loop), "
            f"{rows['fast'][1] / rows['reference'][1]:.2f}x (study, 1 worker); "
            f"steps {f.steps_per_experiment:.0f} vs {r.steps_per_experiment:.0f}"
        )


if __name__ == "__main__":
    main()
