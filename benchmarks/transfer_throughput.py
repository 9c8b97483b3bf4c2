"""E^V throughput against the raw engine time of the very same experiments.

Runs E^V for one object over the states every `--step` degrees with a built-in profile
and prints experiments/s, physics steps per experiment, the raw `mj_step` rate of these
experiments' own steps and the overhead ratio (wall time / time inside `mj_step`).

    PYTHONPATH=src .venv/bin/python benchmarks/transfer_throughput.py \
        [--object o1] [--step 30] [--profile fast] [--set KEY=VALUE ...]
"""

from __future__ import annotations

import argparse

from _engine import parse_sets, timed_experiments
from transfertwin.ots import experiment_states, filter_theta_step
from transfertwin.sim import DockingError, scene_profile
from transfertwin.study import ExperimentSpec


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--object", default="o1")
    parser.add_argument("--step", type=int, default=30, help="θ step of the states run")
    parser.add_argument("--profile", default="fast", help="built-in profile (fast, reference)")
    parser.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                        help="scene override, e.g. physics.pulley_facets=32")  # fmt: skip
    args = parser.parse_args()
    error = DockingError.from_mm_deg(-8.55, 2.84, 1.44)  # real experiment 0
    scene = scene_profile(args.profile, **parse_sets(args.set))
    states = filter_theta_step(experiment_states(), args.step)
    specs = [ExperimentSpec(args.object, s.face, s.conveyor, s.theta_deg, docking_error=error,
                            scene=scene) for s in states]  # fmt: skip
    timed = timed_experiments(specs)
    ok = sum(r.status == "ok" for r in timed.results)
    print(f"object {args.object}, profile {args.profile}: {len(specs)} experiments ({ok} ok), "
          f"{timed.steps_per_experiment:.0f} physics steps each")  # fmt: skip
    print(f"E^V throughput     : {timed.rate:8.2f} experiments/s")
    print(
        f"raw mj_step rate   : {timed.steps / timed.engine_s:8.0f} steps/s  "
        "(same experiments' steps)"
    )
    print(f"engine-bound limit : {len(specs) / timed.engine_s:8.2f} experiments/s")
    print(f"overhead ratio     : {timed.overhead:8.3f}x  (1.0 = all time in mj_step)")


if __name__ == "__main__":
    main()
