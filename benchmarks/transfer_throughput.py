"""E^V throughput against the raw engine time of the very same experiments.

Runs E^V for one object over the states every `--step` degrees, then replays each
experiment's physics with no Python in the loop (`_engine.raw_replay_seconds`) and prints
experiments/s, the raw `mj_step` rate of the same model, and the overhead ratio.

    .venv/bin/python benchmarks/transfer_throughput.py [--object o1] [--step 30]
"""

from __future__ import annotations

import argparse
import time

from _engine import raw_replay_seconds
from transfertwin.ots import experiment_states, filter_theta_step
from transfertwin.sim import DockingError
from transfertwin.study import ExperimentSpec, run_experiment, system_for


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--object", default="o1")
    parser.add_argument("--step", type=int, default=30, help="θ step of the states run")
    args = parser.parse_args()
    error = DockingError.from_mm_deg(-8.55, 2.84, 1.44)  # real experiment 0
    states = filter_theta_step(experiment_states(), args.step)
    specs = [ExperimentSpec(args.object, s.face, s.conveyor, s.theta_deg, docking_error=error)
             for s in states]  # fmt: skip
    system_for(specs[0].object_ref, "m", specs[0].scene)  # compile outside the timing

    t0 = time.perf_counter()
    results = [run_experiment(spec) for spec in specs]
    wall = time.perf_counter() - t0
    raw_s, raw_steps = raw_replay_seconds(specs, results)

    ok = sum(r.status == "ok" for r in results)
    print(f"object {args.object}: {len(specs)} experiments ({ok} ok), "
          f"{raw_steps / len(specs):.0f} physics steps each")  # fmt: skip
    print(f"E^V throughput     : {len(specs) / wall:8.2f} experiments/s")
    print(f"raw mj_step rate   : {raw_steps / raw_s:8.0f} steps/s  (same experiments' steps)")
    print(f"engine-bound limit : {len(specs) / raw_s:8.2f} experiments/s")
    print(f"overhead ratio     : {wall / raw_s:8.2f}x  (1.0 = all time in mj_step)")


if __name__ == "__main__":
    main()
