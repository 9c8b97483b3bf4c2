"""Which parallel backend for the study runner: processes or `mujoco.rollout` threads?

Both step the same compiled scene (a built-in core on running belts) for the same total
number of physics steps, in chunks of one camera period (the study has to evaluate the state
sets after every chunk):

- serial: one `MjData`, `mj_step` in this process (the baseline);
- processes: N spawned processes, each stepping its own scene;
- rollout: one batch of B scenes advanced chunk by chunk by `mujoco.rollout` on N threads,
  reading the states back after every chunk (what a lock-step batched runner would do).

    .venv/bin/python benchmarks/parallel_backends.py [--object o1] [--workers 2]
"""

from __future__ import annotations

import argparse
import multiprocessing as mp
import time

import mujoco
import numpy as np
from mujoco import rollout

from transfertwin.sim import DockingError, SceneConfig
from transfertwin.study import system_for

CHUNK = SceneConfig().steps_per_sample()


def _scene(object_ref: str):
    system = system_for(object_ref, "m", SceneConfig())
    system.reset(DockingError())
    system.place("front", 0.0, -0.325, 0.0)
    for belt in ("left", "right"):
        system.tm.set_belt_speed(belt, 0.15)
        system.tu.set_belt_speed(belt, 0.15)
    return system


def _serial(object_ref: str, steps: int) -> float:
    system = _scene(object_ref)
    t0 = time.perf_counter()
    for _ in range(steps // CHUNK):
        mujoco.mj_step(system.model, system.data, nstep=CHUNK)
        system.observe()
    return time.perf_counter() - t0


def _worker(args: tuple[str, int]) -> float:
    return _serial(*args)


def _processes(object_ref: str, steps: int, workers: int) -> float:
    ctx = mp.get_context("spawn")
    with ctx.Pool(workers) as pool:
        pool.map(_worker, [(object_ref, CHUNK)] * workers)  # warm up: imports, compile
        t0 = time.perf_counter()
        pool.map(_worker, [(object_ref, steps // workers)] * workers)
        return time.perf_counter() - t0


def _rollout(object_ref: str, steps: int, workers: int, batch: int) -> float:
    system = _scene(object_ref)
    model, spec = system.model, int(mujoco.mjtState.mjSTATE_FULLPHYSICS)
    state0 = np.empty(mujoco.mj_stateSize(model, spec))
    mujoco.mj_getState(model, system.data, state0, spec)
    states = np.tile(state0, (batch, 1))
    datas = [mujoco.MjData(model) for _ in range(workers)]
    models = [model] * batch
    t0 = time.perf_counter()
    for _ in range(steps // (CHUNK * batch)):
        out, _ = rollout.rollout(models, datas, states, nstep=CHUNK, persistent_pool=True)
        states = out[:, -1, :].copy()
    rollout.shutdown_persistent_pool()
    return time.perf_counter() - t0


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--object", default="o1")
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--batch", type=int, default=16)
    parser.add_argument("--steps", type=int, default=CHUNK * 16 * 60)
    args = parser.parse_args()
    steps = args.steps
    serial = _serial(args.object, steps)
    procs = _processes(args.object, steps, args.workers)
    roll = _rollout(args.object, steps, args.workers, args.batch)
    print(f"{steps} physics steps of {args.object} on running belts, chunks of {CHUNK} steps")
    print(f"serial mj_step          : {steps / serial:9.0f} steps/s  (baseline)")
    print(f"{args.workers} processes            : {steps / procs:9.0f} steps/s  "
          f"({serial / procs:.2f}x)")  # fmt: skip
    print(f"rollout {args.workers} threads, B={args.batch:<3d}: {steps / roll:9.0f} steps/s  "
          f"({serial / roll:.2f}x)")  # fmt: skip


if __name__ == "__main__":
    main()
