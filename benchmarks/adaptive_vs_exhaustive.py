"""Adaptive against exhaustive sampling: same best/worst state, and at what share of the runs.

Two parts, each printing (a) the share of objects whose adaptive best and worst state equal
the exhaustive one or have an exhaustive success share inside the exhaustive pick's
Clopper–Pearson 95 % interval, and (b) the adaptive runs as a fraction of the exhaustive runs
(targets: >= 95 % and <= 20 %).

* synthetic: `--landscapes` smooth Bernoulli landscapes (`smooth_landscape`) with known
  success probabilities on the 30° state grid; also how often the adaptive pick is truly
  within epsilon of the true best/worst.
* simulator: the built-in cores `--objects` on the `--theta-step` grid, `--runs` runs per
  state, in the scene `--scene` (default: today's defaults; 'gap30': d_gap = 30 mm, a scene
  with failures). The exhaustive study runs for real (MuJoCo, `--workers`); the adaptive
  decisions are then taken on its stored outcomes, which are the outcomes an adaptive study
  would get, since every experiment's seed depends on (object, state, run) only. `--live`
  also runs the adaptive study itself (`run_adaptive`) into its own store and checks that it
  stored exactly the runs the replay asked for, with the same outcomes.

    PYTHONPATH=src .venv/bin/python benchmarks/adaptive_vs_exhaustive.py \
        [--landscapes 200] [--objects o1,o5,...] [--runs 20] [--scene default|gap30] [--live]
"""

from __future__ import annotations

import argparse
import tempfile
import time
from pathlib import Path

import numpy as np

from transfertwin.ots import experiment_states, filter_theta_step
from transfertwin.sim import SceneConfig
from transfertwin.store import SQLiteResultStore
from transfertwin.study import ResampledDockingErrors, StudyPlan, run_study
from transfertwin.study.adaptive import (
    AdaptivePolicy,
    ObjectSampler,
    agrees,
    run_adaptive,
    selection_of_counts,
    simulate_bernoulli,
    smooth_landscape,
)

SCENES = {"default": {}, "gap30": {"gap_m": 0.03}}
OBJECTS = "o1,o5,o9,o14,o18,o23,o28,o32"


def _policy(args: argparse.Namespace) -> AdaptivePolicy:
    return AdaptivePolicy(first_runs=args.first_runs, batch_runs=args.batch, interval=args.interval,
                          confidence=args.confidence, epsilon=args.epsilon)  # fmt: skip


def _line(label: str, n: int, best: int, worst: int, both: int, runs: int, total: int) -> str:
    return (f"{label}: {n} objects; same or inside the exhaustive interval: best {best / n:.1%}, "
            f"worst {worst / n:.1%}, both {both / n:.1%}; runs {runs}/{total} = "
            f"{runs / total:.1%} of exhaustive")  # fmt: skip


def synthetic(args: argparse.Namespace) -> None:
    states = [(s.face, s.conveyor, s.theta_deg) for s in filter_theta_step(experiment_states(), 30)]
    policy = _policy(args)
    best = worst = both = true_best = true_worst = runs = total = 0
    t0 = time.perf_counter()
    for seed in range(args.landscapes):
        r = simulate_bernoulli(smooth_landscape(states, seed), args.synthetic_runs, policy,
                               seed=10_000 + seed)  # fmt: skip
        b, w = r.agrees("best"), r.agrees("worst")
        best, worst, both = best + b, worst + w, both + (b and w)
        true_best += r.true_best - r.p_best <= policy.epsilon
        true_worst += r.p_worst - r.true_worst <= policy.epsilon
        runs, total = runs + r.runs, total + r.budget_runs
    n = args.landscapes
    print(f"synthetic: {n} smooth landscapes x {len(states)} states x {args.synthetic_runs} "
          f"runs; {policy}")  # fmt: skip
    print(_line("synthetic", n, best, worst, both, runs, total), flush=True)
    print(f"synthetic: truly within epsilon={policy.epsilon} of the true extreme: best "
          f"{true_best / n:.1%}, worst {true_worst / n:.1%}; "
          f"{time.perf_counter() - t0:.1f} s")  # fmt: skip


def simulator(args: argparse.Namespace) -> None:
    objects = tuple(args.objects.split(","))
    scene = SceneConfig().with_overrides(**SCENES[args.scene])
    plan = StudyPlan(objects, args.theta_step, args.runs, args.seed,
                     ResampledDockingErrors.from_csv(), scene=scene)  # fmt: skip
    states = [(s.face, s.conveyor, s.theta_deg) for s in plan.states()]
    policy = _policy(args)
    with tempfile.TemporaryDirectory() as tmp:
        t0 = time.perf_counter()
        with SQLiteResultStore(Path(tmp) / "exhaustive.sqlite") as store:
            run_study(plan, store, workers=args.workers)
            rows = list(store.rows())
        secs = time.perf_counter() - t0
        print(f"\nsimulator ({args.scene} scene): {len(objects)} cores x {len(states)} states x "
              f"{args.runs} runs = {len(rows)} exhaustive experiments in {secs:.0f} s")  # fmt: skip
        wins = {(str(r["object_id"]), r["face"], r["conveyor"], int(r["theta_deg"]), int(r["run"])):
                (int(r["success"]) if r["status"] == "ok" else None) for r in rows}  # fmt: skip
        best = worst = both = runs = 0
        targets = {}
        for oid in objects:
            out = {s: [wins[(oid, *s, r)] for r in range(args.runs)] for s in states}
            sampler = ObjectSampler(oid, states, args.runs, policy)
            while not sampler.done:
                sampler.step(out)
            t = sampler.targets
            targets[oid] = t
            k_full = [sum(v == 1 for v in out[s]) for s in states]
            n_full = [sum(v is not None for v in out[s]) for s in states]
            k_ad = [sum(v == 1 for v in out[s][: t[s]]) for s in states]
            n_ad = [sum(v is not None for v in out[s][: t[s]]) for s in states]
            full, stats = selection_of_counts(oid, states, k_full, n_full, policy.window)
            ad, _ = selection_of_counts(oid, states, k_ad, n_ad, policy.window)
            b = agrees((ad.best.face, ad.best.conveyor, ad.best.theta_deg), full, stats, "best")
            w = agrees((ad.worst.face, ad.worst.conveyor, ad.worst.theta_deg), full, stats,
                       "worst")  # fmt: skip
            best, worst, both, runs = best + b, worst + w, both + (b and w), runs + sampler.runs
            share = np.mean([v for s in states for v in out[s] if v is not None])
            print(f"  {oid}: success share {share:.3f}; exhaustive best "
                  f"{full.best.face}/{full.best.conveyor}/{full.best.theta_deg} "
                  f"{full.best.p_hat:.2f} worst {full.worst.face}/{full.worst.conveyor}/"
                  f"{full.worst.theta_deg} {full.worst.p_hat:.2f}; adaptive best "
                  f"{ad.best.face}/{ad.best.conveyor}/{ad.best.theta_deg} ({'ok' if b else 'MISS'})"
                  f" worst {ad.worst.face}/{ad.worst.conveyor}/{ad.worst.theta_deg} "
                  f"({'ok' if w else 'MISS'}); runs {sampler.runs}/{len(states) * args.runs}",
                  flush=True)  # fmt: skip
        print(_line(f"simulator ({args.scene})", len(objects), best, worst, both, runs, len(rows)))
        if args.live:
            _live(args, plan, policy, targets, wins, Path(tmp))


def _live(args, plan: StudyPlan, policy: AdaptivePolicy, targets, wins, tmp: Path) -> None:
    live = StudyPlan(plan.objects, plan.theta_step, plan.runs, plan.seed, plan.docking,
                     scene=plan.scene, sampling="adaptive",
                     sampling_options=tuple(policy.describe().items()))  # fmt: skip
    t0 = time.perf_counter()
    with SQLiteResultStore(tmp / "adaptive.sqlite") as store:
        out = run_adaptive(live, store, workers=args.workers)
        rows = list(store.rows())
    got = {(str(r["object_id"]), r["face"], r["conveyor"], int(r["theta_deg"]), int(r["run"])):
           (int(r["success"]) if r["status"] == "ok" else None) for r in rows}  # fmt: skip
    want = {(o, *s, r) for o, t in targets.items() for s, n in t.items() for r in range(n)}
    same = set(got) == want and all(got[key] == wins[key] for key in got)
    print(f"live adaptive study: {out.ran} runs in {time.perf_counter() - t0:.0f} s "
          f"({out.rate:.2f} exp/s, {out.rounds} object-rounds); same runs and outcomes as the "
          f"replay: {same}")  # fmt: skip


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--landscapes", type=int, default=200, help="synthetic; 0 skips")
    parser.add_argument("--synthetic-runs", type=int, default=50)
    parser.add_argument("--objects", default=OBJECTS, help="built-in cores; '' skips")
    parser.add_argument("--theta-step", type=int, default=30)
    parser.add_argument("--runs", type=int, default=20)
    parser.add_argument("--scene", choices=tuple(SCENES), default="default")
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--first-runs", type=int, default=AdaptivePolicy.first_runs)
    parser.add_argument("--batch", type=int, default=AdaptivePolicy.batch_runs)
    parser.add_argument("--interval", default=AdaptivePolicy.interval)
    parser.add_argument("--confidence", type=float, default=AdaptivePolicy.confidence)
    parser.add_argument("--epsilon", type=float, default=AdaptivePolicy.epsilon)
    parser.add_argument("--live", action="store_true", help="also run the adaptive study")
    args = parser.parse_args()
    if args.landscapes:
        synthetic(args)
    if args.objects:
        simulator(args)


if __name__ == "__main__":
    main()
