"""Study runner throughput on 1 and 2 workers against the raw engine stepping rate.

Runs the same small plan with 1 and with N worker processes into fresh SQLite stores and
prints experiments/s, the scaling ratio, and the engine-bound limit computed from the raw
`mj_step` rate of the same compiled scene measured in the same run.

    .venv/bin/python benchmarks/study_throughput.py [--objects o1,o18] [--runs 2] [--workers 2]
"""

from __future__ import annotations

import argparse
import tempfile
import time
from pathlib import Path

import mujoco
from rich.console import Console

from transfertwin.sim import DockingError
from transfertwin.store import SQLiteResultStore
from transfertwin.study import (
    ExperimentSpec,
    ResampledDockingErrors,
    StudyPlan,
    run_experiment,
    run_study,
    system_for,
)


def _raw_step_rate(object_ref: str, plan: StudyPlan, n: int = 20000) -> float:
    system = system_for(object_ref, "m", plan.scene)
    system.reset(DockingError())
    system.place("front", 0.0, -0.325, 0.0)
    for belt in ("left", "right"):
        system.tm.set_belt_speed(belt, 0.15)
        system.tu.set_belt_speed(belt, 0.15)
    t0 = time.perf_counter()
    mujoco.mj_step(system.model, system.data, nstep=n)
    return n / (time.perf_counter() - t0)


def _timed(plan: StudyPlan, workers: int, tmp: Path) -> tuple[float, int]:
    with SQLiteResultStore(tmp / f"w{workers}.sqlite") as store:
        outcome = run_study(plan, store, workers=workers, console=Console(quiet=True))
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
        # physics steps per experiment, from the first state of each object
        steps = []
        for ref in plan.objects:
            s = plan.states()[0]
            run_experiment(ExperimentSpec(ref, s.face, s.conveyor, s.theta_deg))
            steps.append(system_for(ref, "m", plan.scene).steps_taken)
        raw = sum(_raw_step_rate(ref, plan) for ref in plan.objects) / len(plan.objects)
    per_exp = sum(steps) / len(steps)
    print(
        f"plan: {len(plan.objects)} objects x {len(plan.states())} states x {plan.runs} runs"
        f" = {n} experiments"
    )
    print(f"1 worker           : {rate1:8.2f} experiments/s")
    print(f"{args.workers} workers          : {rate_n:8.2f} experiments/s")
    print(f"scaling            : {rate_n / rate1:8.2f}x  (ideal {args.workers}.00x)")
    print(f"raw mj_step rate   : {raw:8.0f} steps/s (1 thread, same scenes, same run)")
    print(
        f"engine-bound limit : {raw / per_exp:8.2f} experiments/s per worker "
        f"(~{per_exp:.0f} steps/experiment)"
    )
    print(f"1-worker efficiency: {rate1 / (raw / per_exp):8.2f}  (1.0 = all time in mj_step)")


if __name__ == "__main__":
    main()
