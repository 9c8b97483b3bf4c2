"""MuJoCo Warp executor against the CPU backend: throughput and agreement, in the same run.

Runs the same plan (objects x states x runs, resampled real docking errors, default scene)
twice: in this process with MuJoCo on the CPU (`run_experiment`, one core), and as batched
MuJoCo Warp worlds (`WarpExecutor`). Prints exp/s of both and their ratio, batch steps,
the success shares with Clopper–Pearson 95 % intervals (they agree when each share lies in
the other's interval) and the share of experiments with the same outcome.

On a GPU (default device ``cuda``):

    PYTHONPATH=src .venv/bin/python benchmarks/warp_throughput.py \
        [--objects o1,o18] [--theta-step 30] [--runs 8] [--worlds 4096]

``--device cpu`` runs Warp's CPU kernels instead (a functional check, not a speed figure:
use a tiny plan, e.g. ``--theta-step 180 --runs 1 --worlds 4 --t-max 4``).
"""

from __future__ import annotations

import argparse
import os
import time

from transfertwin.sim import SceneConfig
from transfertwin.study import ResampledDockingErrors, StudyPlan
from transfertwin.study.experiment import WarpExecutor, run_experiment
from transfertwin.study.fullstate import clopper_pearson

OUTCOME = ("status", "y1", "y2", "success")


def _share(rows: list[dict[str, object]]) -> str:
    ok = [r for r in rows if r["status"] == "ok"]
    k = sum(int(r["success"]) for r in ok)
    ci = clopper_pearson(k, len(ok))
    return f"{k}/{len(ok)} = {k / max(1, len(ok)):6.1%} [{ci.low:.3f}, {ci.high:.3f}]"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--objects", default="o1,o18")
    parser.add_argument("--theta-step", type=int, default=30)
    parser.add_argument("--runs", type=int, default=8)
    parser.add_argument("--worlds", type=int, default=4096)
    parser.add_argument("--device", default=None, help="Warp device (default: cuda)")
    parser.add_argument("--t-max", type=float, help="override the scene's t_max_s (s)")
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args()
    scene = SceneConfig()
    if args.t_max is not None:
        scene = scene.with_overrides(t_max_s=args.t_max)
    objects = tuple(args.objects.split(","))
    plan = StudyPlan(objects, args.theta_step, args.runs, args.seed,
                     ResampledDockingErrors.from_csv(), scene=scene)  # fmt: skip
    specs = [spec for _, spec in plan.specs({o: o for o in objects})]
    load = os.getloadavg()[0]
    print(f"{len(objects)} objects x {len(plan.states())} states x {args.runs} runs = "
          f"{len(specs)} experiments; {os.cpu_count()} CPUs, load {load:.1f}")  # fmt: skip

    with WarpExecutor(worlds=args.worlds, device=args.device) as ex:
        t0 = time.perf_counter()
        warp_rows = [row for batch in ex.batches(specs) for row in batch]
        warp_s = time.perf_counter() - t0
        print(f"warp ({ex.device}, {args.worlds} worlds): {len(specs) / warp_s:.2f} exp/s "
              f"({warp_s:.1f} s incl. kernel compilation/loading, {ex.batch_steps} batch "
              f"steps)")  # fmt: skip
        host_s = ex.seconds - ex.device_seconds
        print(f"  device (upload, step, download) {ex.device_seconds:.1f} s; host {host_s:.1f} s "
              f"for {ex.resumes} lane turns = {host_s / max(1, ex.resumes) * 1e3:.2f} ms per "
              f"turn, {ex.resumes / len(specs):.0f} turns per experiment")  # fmt: skip
        print(f"  host-bound ceiling of one driver process: {len(specs) / host_s:.1f} exp/s "
              f"(however fast the device)")  # fmt: skip
    for spec in specs[:1]:
        run_experiment(spec)  # compile the CPU scene outside the timing
    t0 = time.perf_counter()
    cpu_rows = [run_experiment(spec).row() for spec in specs]
    cpu_s = time.perf_counter() - t0
    print(f"cpu (MuJoCo, 1 process): {len(specs) / cpu_s:.2f} exp/s ({cpu_s:.1f} s)")
    print(f"ratio warp/cpu: {cpu_s / warp_s:.2f}")

    def key(r: dict[str, object]) -> tuple:
        return (r["object_id"], r["face"], r["conveyor"], r["theta_deg"], r["run"])

    warp_by = {key(r): r for r in warp_rows}
    same = sum(tuple(warp_by[key(c)][k] for k in OUTCOME) == tuple(c[k] for k in OUTCOME)
               for c in cpu_rows)  # fmt: skip
    print(f"success  cpu  {_share(cpu_rows)}")
    print(f"success  warp {_share(warp_rows)}")
    print(f"same outcome (status, y1, y2): {same}/{len(specs)} = {same / len(specs):.1%}")


if __name__ == "__main__":
    main()
