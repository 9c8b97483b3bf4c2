"""Perception in the loop vs ground truth: how often the two give the same outcome (item 6).

Runs E^V (there and, if that worked, back) for a sample of pre-transfer states twice: once
with the OTS controller reading the simulator's exact object state (`sensor="truth"`), once
reading the TM's depth camera (`sensor="perception"`: scan, servo onto the object, one
rendered, detected and tracked frame per controller sample). Two runs agree when status,
y1 and y2 are equal. Prints the agreement with its exact (Clopper–Pearson) 95 % interval,
the disagreeing states, and the wall time of perception over ground truth as a ratio
(the baseline: ground truth in the same process, same states).

    PYTHONPATH=src python benchmarks/perception_agreement.py [--objects o1,o23]
        [--theta-step 90] [--seeds 0] [--max-states N] [--sample-seed 0] [--size 160x120]
"""

from __future__ import annotations

import argparse
import math
import random
import time

from transfertwin.ots import experiment_states, filter_theta_step
from transfertwin.perception import CameraIntrinsics, PerceptionConfig
from transfertwin.study.experiment import ExperimentResult, ExperimentSpec, run_experiment
from transfertwin.study.fullstate import clopper_pearson


def _outcome(r: ExperimentResult) -> tuple[str, int | None, int | None]:
    return (r.status, r.y1, r.y2)


def _show(r: ExperimentResult) -> str:
    t = "-" if math.isnan(r.t_end_s) else f"{r.t_end_s:5.2f} s"
    return f"{r.status:7s} y1={r.y1!s:4s} y2={r.y2!s:4s} t_end={t}"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--objects", default="o1,o23")
    ap.add_argument("--theta-step", type=int, default=90, help="keep θ multiples of this")
    ap.add_argument("--seeds", default="0", help="comma-separated experiment seeds")
    ap.add_argument("--max-states", type=int, default=0, help="random sample of this many")
    ap.add_argument("--sample-seed", type=int, default=0, help="seed of that sample")
    ap.add_argument("--size", default="160x120", help="depth image WIDTHxHEIGHT")
    args = ap.parse_args()
    w, h = (int(v) for v in args.size.split("x"))
    config = PerceptionConfig(intrinsics=CameraIntrinsics(w, h))
    states = filter_theta_step(experiment_states(), args.theta_step)
    seeds = [int(s) for s in args.seeds.split(",")]
    plan = [(o, s, seed) for o in args.objects.split(",") for s in states for seed in seeds]
    if 0 < args.max_states < len(plan):
        keep = sorted(random.Random(args.sample_seed).sample(range(len(plan)), args.max_states))
        plan = [plan[i] for i in keep]
    print(f"{len(plan)} experiments: objects {args.objects}, θ step {args.theta_step}°, "
          f"seeds {args.seeds}, camera {w}x{h}")  # fmt: skip
    agree, t_truth, t_seen, rows = 0, 0.0, 0.0, []
    for k, (obj, state, seed) in enumerate(plan, start=1):
        spec = ExperimentSpec(obj, state.face, state.conveyor, state.theta_deg, seed=seed)
        t0 = time.perf_counter()
        truth = run_experiment(spec)
        t1 = time.perf_counter()
        seen = run_experiment(spec, sensor="perception", perception=config)
        t2 = time.perf_counter()
        t_truth, t_seen = t_truth + t1 - t0, t_seen + t2 - t1
        same = _outcome(truth) == _outcome(seen)
        agree += same
        label = f"{obj} {state.face:5s} {state.conveyor:5s} θ={state.theta_deg:4d} seed {seed}"
        rows.append((label, truth, seen, same))
        print(f"[{k:3d}/{len(plan)}] {label}  truth: {_show(truth)} | perception: {_show(seen)}"
              f"  {'agree' if same else 'DIFFER'}  ({t1 - t0:.1f} s / {t2 - t1:.1f} s)",
              flush=True)  # fmt: skip
    ci = clopper_pearson(agree, len(plan))
    print(f"\nagreement (status, y1, y2): {agree}/{len(plan)} = {agree / len(plan):.3f}, "
          f"95 % Clopper-Pearson [{ci.low:.3f}, {ci.high:.3f}]")  # fmt: skip
    both_ok = [(t, s) for _, t, s, _ in rows if t.status == s.status == "ok"]
    if both_ok:
        k = sum(t.success == s.success for t, s in both_ok)
        ci = clopper_pearson(k, len(both_ok))
        print(f"success agreement where both ran: {k}/{len(both_ok)}, "
              f"[{ci.low:.3f}, {ci.high:.3f}]")  # fmt: skip
        dt = [abs(t.t_end_s - s.t_end_s) for t, s in both_ok if t.success == s.success == 1]
        if dt:
            print(f"|t_end difference| where both succeeded: median {sorted(dt)[len(dt) // 2]:.3f}"
                  f" s, max {max(dt):.3f} s")  # fmt: skip
    for label, truth, seen, same in rows:
        if not same:
            print(f"  differ: {label}: truth {_show(truth)}; perception {_show(seen)} "
                  f"{seen.message}")  # fmt: skip
    print(f"wall time: perception {t_seen:.1f} s, ground truth {t_truth:.1f} s, "
          f"ratio {t_seen / max(t_truth, 1e-9):.1f}x")  # fmt: skip


if __name__ == "__main__":
    main()
