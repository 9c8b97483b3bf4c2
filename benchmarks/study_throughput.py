"""Study runner throughput on 1 and 2 workers against the raw engine stepping rate.

Runs the same small plan with 1 and with N worker processes into fresh SQLite stores and
prints experiments/s, the scaling ratio, and the engine-bound limit computed from the raw
`mj_step` rate of the same compiled scene measured in the same run.

    .venv/bin/python benchmarks/study_throughput.py [--objects o1,o18] [--runs 2] [--workers 2]
"""

from __future__ import annotations

import argparse
import tempfile
from pathlib import Path

from _engine import raw_replay_seconds
from transfertwin.store import SQLiteResultStore
from transfertwin.study import (
    ResampledDockingErrors,
    StudyPlan,
    run_experiment,
    run_study,
)


def _timed(plan: StudyPlan, workers: int, tmp: Path) -> tuple[float, int]:
    with SQLiteResultStore(tmp / f"w{workers}.sqlite") as store:
        outcome = run_study(plan, store, workers=workers)
    return outcome.rate, outcome.ran


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--objects", default="o1,o18")
    parser.add_argument("--theta-step", type=int, default=45)
    parser.add_argument("--runs", type=int, default=2)
    parser.add_argument("--workers", type=int, default=2)
    args = parser.parse_args()
    plan = StudyPlan(tuple(args.objects.split(",")), args.theta_step, args.runs, 0,
                     ResampledDockingErrors.from_csv())  # fmt: skip
    with tempfile.TemporaryDirectory() as tmp:
        rate1, n = _timed(plan, 1, Path(tmp))
        rate_n, _ = _timed(plan, args.workers, Path(tmp))
        # engine alone on the same plan's first experiments, replayed without Python
        ids = {ref: ref for ref in plan.objects}
        sample = [spec for _, spec in plan.specs(ids)][:: max(1, n // 20)]
        raw_s, raw_steps = raw_replay_seconds(sample, [run_experiment(s) for s in sample])
    engine = len(sample) / raw_s
    print(
        f"plan: {len(plan.objects)} objects x {len(plan.states())} states x {plan.runs} runs"
        f" = {n} experiments"
    )
    print(f"1 worker           : {rate1:8.2f} experiments/s")
    print(f"{args.workers} workers          : {rate_n:8.2f} experiments/s")
    print(f"scaling            : {rate_n / rate1:8.2f}x  (ideal {args.workers}.00x)")
    print(f"raw mj_step rate   : {raw_steps / raw_s:8.0f} steps/s (same experiments, 1 thread)")
    print(f"engine-bound limit : {engine:8.2f} experiments/s per worker "
          f"(~{raw_steps / len(sample):.0f} steps/experiment)")  # fmt: skip
    print(f"1-worker efficiency: {rate1 / engine:8.2f}  (1.0 = all time in mj_step)")


if __name__ == "__main__":
    main()
