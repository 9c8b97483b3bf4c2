"""Cost of one physics step on states the experiments really visit, per engine setting.

Runs the default study states of each object (θ step 90), keeps ~15 % of the camera
samples' full integration states, then replays each kept state for one camera period (13
steps) under every variant below, interleaved and repeated, and prints µs per step and
the ratio to 'sensors every step' (how `VirtualTransferSystem.step` stepped before the
seventh session). The variants change only MuJoCo flags on the same compiled model:

- sensors every step: the light barriers' rangefinders run in every step;
- sensors at sample end: they run only in a sample's last step (`VirtualTransferSystem.step`:
  the dynamics do not read them, so results are the same bits);
- multi-CCD flipped: the scene's multi-CCD setting the other way round (one contact per
  convex pair when off).

    PYTHONPATH=src .venv/bin/python benchmarks/step_cost.py [--objects o1,o18] \
        [--repeats 5] [--set KEY=VALUE ...]
"""

from __future__ import annotations

import argparse
import statistics
import time

import mujoco
import numpy as np

from _engine import parse_sets
from transfertwin.objects import load_object
from transfertwin.ots import experiment_states, filter_theta_step
from transfertwin.sim import OBJECT_BODY, DockingError, VirtualTransferSystem, scene_profile
from transfertwin.study import ExperimentSpec, run_experiment

SIG = mujoco.mjtState.mjSTATE_INTEGRATION
SENSOR = int(mujoco.mjtDisableBit.mjDSBL_SENSOR)
MULTICCD = int(mujoco.mjtDisableBit.mjDSBL_MULTICCD)


def _visited_states(system: VirtualTransferSystem, specs, share: float) -> list[np.ndarray]:
    """Full integration states at a random `share` of the camera samples of `specs`."""
    kept, rng, step = [], np.random.default_rng(0), system.step
    size = mujoco.mj_stateSize(system.model, SIG)

    def recording(n: int) -> None:
        if rng.random() < share:
            buf = np.empty(size)
            mujoco.mj_getState(system.model, system.data, buf, SIG)
            kept.append(buf)
        step(n)

    system.step = recording
    try:
        for spec in specs:
            run_experiment(spec, system=system)
    finally:
        system.step = step
    return kept


def _us_per_step(model, data, states, flags: int, sensors_last: bool, n: int) -> float:
    opt = model.opt
    t0 = time.perf_counter()
    for state in states:
        mujoco.mj_setState(model, data, state, SIG)
        if sensors_last:
            opt.disableflags = flags | SENSOR
            mujoco.mj_step(model, data, nstep=n - 1)
            opt.disableflags = flags
            mujoco.mj_step(model, data)
        else:
            opt.disableflags = flags
            mujoco.mj_step(model, data, nstep=n)
    opt.disableflags = flags
    return (time.perf_counter() - t0) / (len(states) * n) * 1e6


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--objects", default="o1,o18")
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                        help="scene override, e.g. physics.max_hulls=none")  # fmt: skip
    args = parser.parse_args()
    scene = scene_profile("fast", **parse_sets(args.set))
    error = DockingError.from_mm_deg(-8.55, 2.84, 1.44)  # real experiment 0
    n = scene.steps_per_sample()
    for ref in args.objects.split(","):
        obj = load_object(ref)
        system = VirtualTransferSystem(obj.hulls, obj.mass.mass_kg, obj.mass.com_m,
                                       obj.mass.inertia_kg_m2, scene,
                                       feature_hulls=obj.feature_hulls)  # fmt: skip
        grid = filter_theta_step(experiment_states(), 90)
        specs = [ExperimentSpec(ref, s.face, s.conveyor, s.theta_deg, docking_error=error,
                                scene=scene) for s in grid]  # fmt: skip
        states = _visited_states(system, specs, 0.15)
        model, data = system.model, mujoco.MjData(system.model)
        base = int(model.opt.disableflags)
        variants = {
            "sensors every step": (base, False),
            "sensors at sample end": (base, True),
            "multi-CCD flipped": (base ^ MULTICCD, True),
        }
        times: dict[str, list[float]] = {k: [] for k in variants}
        for _ in range(args.repeats):
            for name, (flags, last) in variants.items():
                times[name].append(_us_per_step(model, data, states, flags, last, n))
        multiccd = "off" if base & MULTICCD else "on"
        in_scene = int(model.body(OBJECT_BODY).geomnum[0])  # hulls after the budget
        print(f"{ref}: {len(obj.hulls)} hulls -> {in_scene} in the scene, "
              f"multi-CCD {multiccd}; {len(states)} visited states x {n} steps x "
              f"{args.repeats} repeats")  # fmt: skip
        first = statistics.median(times["sensors every step"])
        for name, values in times.items():
            med = statistics.median(values)
            print(f"  {name:22s} {med:7.1f} us/step   x{first / med:5.2f}")


if __name__ == "__main__":
    main()
