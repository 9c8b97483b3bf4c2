"""E^V throughput against the raw `mj_step` rate of the same compiled model.

Prints experiments per second, physics steps per experiment, the raw stepping rate of the
same model measured in the same run, and the overhead ratio (time spent outside `mj_step`).

    .venv/bin/python benchmarks/transfer_throughput.py [--object o1] [--n 24]
"""

from __future__ import annotations

import argparse
import time

import mujoco

from transfertwin.ots import experiment_states, filter_theta_step
from transfertwin.sim import DockingError
from transfertwin.study import ExperimentSpec, run_experiment, system_for


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--object", default="o1")
    parser.add_argument("--step", type=int, default=30, help="θ step of the states run")
    args = parser.parse_args()
    error = DockingError.from_mm_deg(-8.55, 2.84, 1.44)
    states = filter_theta_step(experiment_states(), args.step)
    specs = [ExperimentSpec(args.object, s.face, s.conveyor, s.theta_deg, docking_error=error)
             for s in states]  # fmt: skip
    system = system_for(specs[0].object_ref, "m", specs[0].scene)  # compile outside timing

    steps = 0
    t0 = time.perf_counter()
    results = []
    for spec in specs:
        results.append(run_experiment(spec))
        steps += system.steps_taken
    wall = time.perf_counter() - t0
    exp_rate = len(specs) / wall

    # Raw engine rate: the same model, the same kind of state (object on running belts).
    system.reset(error)
    system.place("front", 0.0, -0.325, 0.0)
    for belt in ("left", "right"):
        system.tm.set_belt_speed(belt, 0.15)
        system.tu.set_belt_speed(belt, 0.15)
    n_raw = min(steps, 20000)
    t0 = time.perf_counter()
    mujoco.mj_step(system.model, system.data, nstep=n_raw)
    raw_rate = n_raw / (time.perf_counter() - t0)

    ideal = raw_rate / (steps / len(specs))
    ok = sum(r.status == "ok" for r in results)
    print(
        f"object {args.object}: {len(specs)} experiments ({ok} ok), "
        f"{steps / len(specs):.0f} physics steps each"
    )
    print(f"E^V throughput     : {exp_rate:8.2f} experiments/s")
    print(f"raw mj_step rate   : {raw_rate:8.0f} steps/s  (same model, same run)")
    print(f"engine-bound limit : {ideal:8.2f} experiments/s")
    print(f"overhead ratio     : {ideal / exp_rate:8.2f}x  (1.0 = all time in mj_step)")


if __name__ == "__main__":
    main()
