"""Shared baseline of the benchmarks: the raw engine time of the same experiments.

`raw_replay_seconds` re-runs each experiment's physics with no Python in the loop: the same
placement and settling, then the belts forward for transfer 1's duration and backward for
transfer 2's, each as a single `mj_step(nstep=...)` call. The result is the time the engine
alone needs for exactly the steps the experiments took.
"""

from __future__ import annotations

import math
import time
from collections.abc import Sequence

import mujoco

from transfertwin.study import ExperimentResult, ExperimentSpec, system_for


def _drive(system, speed: float) -> None:
    for belt in ("left", "right"):
        system.tm.set_belt_speed(belt, speed)
        system.tu.set_belt_speed(belt, speed)


def raw_replay_seconds(
    specs: Sequence[ExperimentSpec], results: Sequence[ExperimentResult]
) -> tuple[float, int]:
    """(seconds, physics steps) of the engine alone for the given experiments."""
    total, steps = 0.0, 0
    for spec, res in zip(specs, results, strict=True):
        system = system_for(spec.object_ref, spec.units, spec.scene)
        dt = system.model.opt.timestep
        settle = round(spec.scene.placement.settle_time_s / dt)
        n1 = 0 if math.isnan(res.t_end_1_s) else round(res.t_end_1_s / dt)
        n2 = 0 if math.isnan(res.t_end_2_s) else settle + round(res.t_end_2_s / dt)
        speed = spec.scene.layout.belt_speed_m_s
        system.reset(spec.docking_error)
        system.place(spec.face, math.radians(spec.theta_deg), -0.325, 0.0)
        t0 = time.perf_counter()
        mujoco.mj_step(system.model, system.data, nstep=settle)
        _drive(system, speed)
        if n1:
            mujoco.mj_step(system.model, system.data, nstep=n1)
        _drive(system, -speed)
        if n2:
            mujoco.mj_step(system.model, system.data, nstep=n2)
        total += time.perf_counter() - t0
        steps += settle + n1 + n2
    return total, steps
