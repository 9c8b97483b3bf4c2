"""Shared baseline of the benchmarks: the raw engine time of the same experiments.

Every `VirtualTransferSystem` times its own `mj_step` calls (`engine_seconds`,
`engine_steps`): that is the time the engine alone needs for exactly the steps the
experiments took, measured on the very same calls. `timed_experiments` runs specs in this
process and returns wall time, engine time and steps, so overhead = wall / engine.
"""

from __future__ import annotations

import time
from collections.abc import Sequence
from dataclasses import dataclass

from transfertwin.study import ExperimentResult, ExperimentSpec, run_experiment, system_for


@dataclass(frozen=True)
class Timed:
    """Experiments run in one process: results, wall and engine seconds, engine steps."""

    results: tuple[ExperimentResult, ...]
    wall_s: float
    engine_s: float
    steps: int

    @property
    def rate(self) -> float:
        return len(self.results) / self.wall_s

    @property
    def steps_per_experiment(self) -> float:
        return self.steps / len(self.results)

    @property
    def overhead(self) -> float:
        """Wall time over the time spent in mj_step (1.0 = all time in the engine)."""
        return self.wall_s / self.engine_s


def timed_experiments(specs: Sequence[ExperimentSpec]) -> Timed:
    """Run `specs` in order in this process (compiling each scene outside the timing)."""
    results, wall, engine, steps = [], 0.0, 0.0, 0
    for spec in specs:
        system = system_for(spec.object_ref, spec.units, spec.scene)
        s0, e0 = system.engine_steps, system.engine_seconds
        t0 = time.perf_counter()
        results.append(run_experiment(spec))
        wall += time.perf_counter() - t0
        engine += system.engine_seconds - e0
        steps += system.engine_steps - s0
    return Timed(tuple(results), wall, engine, steps)


def parse_sets(items: Sequence[str]) -> dict[str, object]:
    """Scene overrides from ``KEY=VALUE`` strings (`SceneConfig.with_overrides` keys);
    a value is read as an int, a float, none/true/false, or else kept as text."""
    out: dict[str, object] = {}
    for item in items:
        key, sep, text = item.partition("=")
        if not sep or not key:
            raise SystemExit(f"--set needs KEY=VALUE, got {item!r}")
        value: object = text
        low = text.lower()
        if low in ("none", "true", "false"):
            value = {"none": None, "true": True, "false": False}[low]
        else:
            for kind in (int, float):
                try:
                    value = kind(text)
                    break
                except ValueError:
                    pass
        out[key] = value
    return out
