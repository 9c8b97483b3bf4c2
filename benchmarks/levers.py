"""Speed levers, each against the fast defaults and the 'reference' profile, in one run.

Every variant is a set of scene overrides on top of the fast defaults (`--set` adds
overrides to all variants and to the reference, e.g. the prism-pulley scene). The same
experiments (objects x states every `--theta-step` degrees x `--runs` seeds, real
experiment 0's docking error) run under every variant, interleaved experiment by
experiment so that a shared machine's load falls on all variants alike. Per variant it
prints physics steps per experiment, exp/s and its ratio to `--baseline` (default 'still',
the stall rule the defaults had before), experiments per CPU second (what one core gives
when it is not shared), the overhead (wall time / time inside `mj_step`), the success
share with its Clopper–Pearson 95 % interval, the share of experiments with the
reference's outcome, and whether the shares agree (each inside the other's interval).

    PYTHONPATH=src .venv/bin/python benchmarks/levers.py --objects o1,o18 --theta-step 90 \
        --set physics.pulley_facets=32 --set layout.pulley_radius_m=0.0125 \
        [--variants still,fast,stall3,camera7.5,dt10] [--runs 1]
"""

from __future__ import annotations

import argparse
import time

from _engine import parse_sets
from transfertwin.ots import experiment_states, filter_theta_step
from transfertwin.sim import DockingError, scene_profile
from transfertwin.study import ExperimentSpec, run_experiment
from transfertwin.study.validation import Agreement, SideOutcome

#: Variant name -> overrides of the fast defaults ('reference' is the reference profile).
VARIANTS: dict[str, dict[str, object]] = {
    "fast": {},
    "still": {"stall_mode": "still"},  # the stall rule before 'progress' became the default
    "stall3": {"stall_time_s": 3.0},
    "camera7.5": {"camera_rate_hz": 7.5},
    "camera5": {"camera_rate_hz": 5.0},
    "dt8": {"physics.timestep_s": 0.008},
    "dt10": {"physics.timestep_s": 0.01},
    "dt10-it100": {
        "physics.timestep_s": 0.01,
        "physics.iterations": 100,
        "physics.tolerance": 1e-10,
    },
    "tol1e-6": {"physics.tolerance": 1e-6},
    "it20": {"physics.iterations": 20, "physics.ls_iterations": 10},
    "hulls8": {"physics.max_hulls": 8},
    "hulls4": {"physics.max_hulls": 4},
    "nomulticcd": {"physics.multiccd": False},
    "hulls8-nomulticcd": {"physics.max_hulls": 8, "physics.multiccd": False},
    "hulls4-nomulticcd": {"physics.max_hulls": 4, "physics.multiccd": False},
    "stall3-cam7.5": {"stall_time_s": 3.0, "camera_rate_hz": 7.5},
    "combo": {
        "stall_time_s": 3.0,
        "camera_rate_hz": 7.5,
        "physics.timestep_s": 0.01,
        "physics.iterations": 100,
        "physics.tolerance": 1e-10,
        "physics.max_hulls": 8,
    },
}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--objects", default="o1,o18")
    parser.add_argument("--theta-step", type=int, default=90)
    parser.add_argument("--runs", type=int, default=1, help="seeds per state")
    parser.add_argument("--variants", default=",".join(VARIANTS))
    parser.add_argument("--baseline", default="still", help="variant the ratios refer to")
    parser.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                        help="scene override for every variant and the reference")  # fmt: skip
    args = parser.parse_args()
    base = parse_sets(args.set)
    names = args.variants.split(",")
    unknown = set(names) - set(VARIANTS)
    if unknown:
        parser.error(f"unknown variant(s): {', '.join(sorted(unknown))}")
    scenes = {n: scene_profile("fast", **base, **VARIANTS[n]) for n in names}
    scenes["reference"] = scene_profile("reference", **base)
    error = DockingError.from_mm_deg(-8.55, 2.84, 1.44)  # real experiment 0
    states = filter_theta_step(experiment_states(), args.theta_step)
    specs = [
        ExperimentSpec(
            o, s.face, s.conveyor, s.theta_deg, docking_error=error, run=r, seed=1000 * r + i
        )
        for o in args.objects.split(",")
        for r in range(args.runs)
        for i, s in enumerate(states)
    ]
    print(f"{len(specs)} experiments per variant; overrides {base or 'none'}", flush=True)
    systems, tally = {}, {n: [[], 0, 0, 0.0, 0.0, 0.0] for n in scenes}  # outcomes, not ok, ...
    for spec in specs:
        for name, scene in scenes.items():
            key = (spec.object_ref, name)
            if key not in systems:
                systems[key] = _fresh(spec.object_ref, scene)
            system = systems[key]
            s0, e0 = system.engine_steps, system.engine_seconds
            t0, c0 = time.perf_counter(), time.process_time()
            res = run_experiment(_with(spec, scene), system=system)
            row = tally[name]
            row[3] += time.perf_counter() - t0
            row[5] += time.process_time() - c0
            row[4] += system.engine_seconds - e0
            row[2] += system.engine_steps - s0
            row[0].append(int(res.status == "ok" and res.success == 1))
            row[1] += res.status != "ok"
    sides = {n: SideOutcome(sum(r[0]), len(r[0]), r[1], r[2], r[3], tuple(r[0]))
             for n, r in tally.items()}  # fmt: skip
    base_name = args.baseline if args.baseline in sides else next(iter(sides))
    base_rate = sides[base_name].rate
    print(f"\n{'variant':<14} {'steps/exp':>9} {'exp/s':>7} {'x ' + base_name:>8} "
          f"{'exp/CPU-s':>9} {'overhead':>8} {'success':>18} {'same as ref':>11}  "
          "agreement")  # fmt: skip
    for name, side in sides.items():
        agree = Agreement(name, side, sides["reference"])
        ci = side.interval
        overhead = tally[name][3] / tally[name][4]
        cpu_rate = side.n / tally[name][5]
        print(f"{name:<14} {side.steps / side.n:9.0f} {side.rate:7.2f} "
              f"{side.rate / base_rate:8.2f} {cpu_rate:9.2f} {overhead:8.3f} "
              f"{side.share:6.1%} [{ci.low:.2f},{ci.high:.2f}] "
              f"{agree.paired_same / side.n:11.1%}  {'AGREE' if agree.agree else 'DIFFER'}"
              f"{'' if side.not_ok == 0 else f' ({side.not_ok} not ok)'}")  # fmt: skip


def _fresh(object_ref: str, scene):
    """A system of its own per (object, variant): `system_for` caches only two."""
    from transfertwin.objects import load_object
    from transfertwin.sim import VirtualTransferSystem

    obj = load_object(object_ref)
    return VirtualTransferSystem(obj.hulls, obj.mass.mass_kg, obj.mass.com_m,
                                 obj.mass.inertia_kg_m2, scene,
                                 feature_hulls=obj.feature_hulls)  # fmt: skip


def _with(spec: ExperimentSpec, scene) -> ExperimentSpec:
    import dataclasses

    return dataclasses.replace(spec, scene=scene)


if __name__ == "__main__":
    main()
