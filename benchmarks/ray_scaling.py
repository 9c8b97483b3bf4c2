"""Study throughput on local processes and on Ray, in one run, and the projection it implies.

The same plan (objects x states x runs, resampled real docking errors, default scene) runs
into a fresh SQLite store four ways:

- local, 1 worker (in this process);
- local, N worker processes (spawned by the call);
- Ray with N CPUs, started by this script (`RayExecutor`; Ray's own start-up is printed
  apart), cold: its worker processes import and compile on their first chunk;
- the same Ray again with plan seed 1, warm: the steady state of a long study.

Each prints the CPU seconds per experiment of this process and all its descendants (worker
processes, and Ray's own processes for Ray): on a shared machine wall-clock rates depend on
the other load, CPU time much less, and it is what a dedicated core would need. And two
wall-clock rates: "call" = experiments over the seconds of the `run_study` call (worker
start-up included: what a short study sees) and "steady" = the experiments stored after
the first batch per worker over the time since (start-up mostly excluded). It prints the
ratios Ray/local and the wall time of the study's 1,709,400 experiments projected from the
warm CPU seconds per experiment (docs/scaling.md).

    PYTHONPATH=src .venv/bin/python benchmarks/ray_scaling.py \
        [--objects o1] [--theta-step 30] [--runs 2] [--workers 2] [--chunk-size 4]

Ray's files go to ``RAY_TMPDIR`` (default: a temporary folder here); set ``RAY_AUTH_MODE``
and ``RAY_AUTH_TOKEN`` to keep Ray from writing a token to ~/.ray (Ray >= 2.5x).
"""

from __future__ import annotations

import argparse
import os
import tempfile
import time
from pathlib import Path

from transfertwin.store import SQLiteResultStore
from transfertwin.study import RayExecutor, ResampledDockingErrors, StudyPlan, run_study

FULL_STUDY = 1_709_400  # 37 cores x 924 states x 50 runs (Eq. 6.20)


_TICK = os.sysconf("SC_CLK_TCK")


def _tree_cpu_s() -> float:
    """CPU seconds of this process, its reaped children and every live descendant."""
    stats = {}
    for entry in Path("/proc").iterdir():
        if entry.name.isdigit():
            try:
                fields = (entry / "stat").read_text().rsplit(")", 1)[1].split()
            except OSError:
                continue
            stats[int(entry.name)] = (int(fields[1]), sum(int(f) for f in fields[11:15]))
    mine, total, grew = {os.getpid()}, 0, True
    while grew:
        new = {pid for pid, (ppid, _) in stats.items() if ppid in mine} - mine
        mine |= new
        grew = bool(new)
    total = sum(stats[pid][1] for pid in mine if pid in stats)
    return total / _TICK


def _rates(plan: StudyPlan, db: Path, skip: int, **kwargs: object) -> tuple[float, float, float]:
    """(call rate, steady rate after the first `skip` results, CPU s per experiment)."""
    cpu0 = _tree_cpu_s()
    stamps: list[tuple[int, float]] = []

    def tick(done: int, total: int) -> None:
        stamps.append((done, time.perf_counter()))

    with SQLiteResultStore(db) as store:
        outcome = run_study(plan, store, on_progress=tick, **kwargs)  # type: ignore[arg-type]
    assert outcome.ran == plan.n_experiments, outcome
    cpu = (_tree_cpu_s() - cpu0) / outcome.ran
    first = next((d, t) for d, t in stamps if d >= skip)
    end = stamps[-1]
    return outcome.rate, (end[0] - first[0]) / (end[1] - first[1]), cpu


def _hours(rate: float) -> str:
    h = FULL_STUDY / rate / 3600
    return f"{h:8.1f} h" if h >= 1 else f"{h * 60:8.1f} min"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--objects", default="o1")
    parser.add_argument("--theta-step", type=int, default=30)
    parser.add_argument("--runs", type=int, default=2)
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--chunk-size", type=int, default=4)
    parser.add_argument("--nodes", type=int, default=8, help="N of the N-node projection")
    parser.add_argument("--node-cores", type=int, default=16, help="cores per projected node")
    args = parser.parse_args()
    docking = ResampledDockingErrors.from_csv()
    objects = tuple(args.objects.split(","))

    def plan(seed: int) -> StudyPlan:
        return StudyPlan(objects, args.theta_step, args.runs, seed, docking)

    n, w = plan(0).n_experiments, args.workers
    print(f"{n} experiments per configuration ({','.join(objects)}, theta step "
          f"{args.theta_step}, {args.runs} runs); load average {os.getloadavg()[0]:.1f} "
          f"on {os.cpu_count()} CPUs", flush=True)  # fmt: skip
    rates: dict[str, tuple[float, float, float]] = {}

    def show(label: str, extra: str = "") -> None:
        call, steady, cpu = rates[label]
        print(f"{label:<12} {cpu:6.3f} CPU s/exp   wall: call {call:5.2f} exp/s, "
              f"steady {steady:5.2f} exp/s{extra}", flush=True)  # fmt: skip

    with tempfile.TemporaryDirectory(prefix="rs", dir="/tmp") as tmp:
        os.environ.setdefault("RAY_TMPDIR", tmp)  # short: Ray's socket paths are long
        rates["local 1w"] = _rates(plan(0), Path(tmp, "l1.sqlite"), 1, workers=1)
        show("local 1w")
        rates[f"local {w}w"] = _rates(plan(0), Path(tmp, "ln.sqlite"), w, workers=w)
        show(f"local {w}w")
        t0 = time.perf_counter()
        with RayExecutor(workers=w, chunk_size=args.chunk_size) as ray:
            start_s = time.perf_counter() - t0
            rates["Ray cold"] = _rates(plan(0), Path(tmp, "r.sqlite"), w * args.chunk_size,
                                       executor=ray)  # fmt: skip
            show("Ray cold", f"   (Ray start-up {start_s:.1f} s, not in either)")
            rates["Ray warm"] = _rates(plan(1), Path(tmp, "r2.sqlite"), w * args.chunk_size,
                                       executor=ray)  # fmt: skip
            show("Ray warm", "   (same Ray, workers compiled; plan seed 1)")
    one, local_n = rates["local 1w"], rates[f"local {w}w"]
    cold, warm = rates["Ray cold"], rates["Ray warm"]
    print(
        f"\nratio Ray cold / local {w}w (both start {w} fresh workers): "
        f"CPU s/exp {cold[2] / local_n[2]:.2f}, wall exp/s {cold[0] / local_n[0]:.2f}"
    )
    print(f"ratio Ray warm / local 1w (both warm, CPU s/exp): {warm[2] / one[2]:.2f}")
    print(f"ratio local {w}w / local 1w (wall exp/s, call): {local_n[0] / one[0]:.2f}")
    # Projection: dedicated cores each doing 1 / (CPU s per experiment) experiments per second
    # of a warm worker (the study is embarrassingly parallel and runs for hours, so start-up
    # is amortised): local 1w for local cores, Ray warm for the cluster. Hyper-threads,
    # memory bandwidth and the driver's store writes at high rates are not modelled.
    core, ray_core = 1 / one[2], 1 / warm[2]
    cluster = args.nodes * args.node_cores
    print(
        f"\nprojected wall time of the {FULL_STUDY:,}-experiment study on dedicated cores "
        f"({core:.2f} exp/s per core locally, {ray_core:.2f} on Ray, from CPU time):"
    )
    print(f"  {w} cores                     {_hours(w * core)}")
    print(f"  16 cores                    {_hours(16 * core)}")
    print(f"  {args.nodes} nodes x {args.node_cores} cores (Ray)  {_hours(cluster * ray_core)}")
    best = max(local_n[1], warm[1])
    print(
        f"  (at the best steady wall rate measured on this shared machine, {best:.2f} "
        f"exp/s on {w} CPUs: {_hours(best).strip()})"
    )


if __name__ == "__main__":
    main()
