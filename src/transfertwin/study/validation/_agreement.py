"""Agreement of two scene settings (e.g. the fast defaults against the 'reference' profile).

The same experiments — same objects, states, seeds and docking errors — run under both
scenes; the success shares agree when each lies inside the other's Clopper–Pearson 95 %
interval. Results that are not 'ok' count as failures (as in the calibration). Engine
steps and wall time are tallied per side, so one run also gives the speed-up.
"""

from __future__ import annotations

import dataclasses
import time
from collections.abc import Sequence
from dataclasses import dataclass

from transfertwin.sim import SceneConfig
from transfertwin.study.experiment import (
    ExperimentResult,
    ExperimentSpec,
    run_experiment,
    system_for,
)
from transfertwin.study.fullstate import Interval, clopper_pearson

__all__ = ["Agreement", "SideOutcome", "compare_scenes", "run_side"]


@dataclass(frozen=True)
class SideOutcome:
    """One scene's results on the common experiments."""

    successes: int
    n: int
    not_ok: int
    steps: int
    seconds: float
    outcomes: tuple[int, ...]

    @property
    def share(self) -> float:
        """Success share (non-'ok' results count as failures)."""
        return self.successes / self.n if self.n else float("nan")

    @property
    def interval(self) -> Interval:
        """Clopper–Pearson 95 % interval of the share."""
        return clopper_pearson(self.successes, self.n)

    @property
    def rate(self) -> float:
        """Experiments per second (one process)."""
        return self.n / self.seconds if self.seconds > 0 else float("nan")


@dataclass(frozen=True)
class Agreement:
    """Fast vs reference on the same experiments."""

    label: str
    fast: SideOutcome
    reference: SideOutcome

    @property
    def agree(self) -> bool:
        """Each share lies inside the other's Clopper–Pearson 95 % interval."""
        f, r = self.fast, self.reference
        return r.interval.low <= f.share <= r.interval.high and (
            f.interval.low <= r.share <= f.interval.high
        )

    @property
    def paired_same(self) -> int:
        """Experiments with the same outcome on both sides."""
        return sum(a == b for a, b in zip(self.fast.outcomes, self.reference.outcomes, strict=True))

    def line(self) -> str:
        """One human-readable summary line."""
        f, r = self.fast, self.reference
        fi, ri = f.interval, r.interval
        return (
            f"{self.label:<14} n={f.n:4d}  fast {f.successes:4d} = {f.share:6.1%} "
            f"[{fi.low:.3f}, {fi.high:.3f}]  ref {r.successes:4d} = {r.share:6.1%} "
            f"[{ri.low:.3f}, {ri.high:.3f}]  paired same {self.paired_same / f.n:6.1%}  "
            f"{'AGREE' if self.agree else 'DIFFER'}"
        )


def _outcome(res: ExperimentResult) -> int:
    return int(res.status == "ok" and res.success == 1)


def run_side(specs: Sequence[ExperimentSpec], scene: SceneConfig) -> SideOutcome:
    """Run `specs` with `scene` in this process; count successes, steps and time."""
    outcomes, steps, not_ok, seconds = [], 0, 0, 0.0
    for spec in specs:
        spec = dataclasses.replace(spec, scene=scene)
        system = system_for(spec.object_ref, spec.units, scene)  # compile outside the timing
        before = system.engine_steps
        t0 = time.perf_counter()
        res = run_experiment(spec)
        seconds += time.perf_counter() - t0
        steps += system.engine_steps - before
        outcomes.append(_outcome(res))
        not_ok += res.status != "ok"
    return SideOutcome(sum(outcomes), len(outcomes), not_ok, steps, seconds, tuple(outcomes))


def compare_scenes(
    label: str,
    specs: Sequence[ExperimentSpec],
    fast: SceneConfig,
    reference: SceneConfig,
) -> Agreement:
    """Run the same experiments under both scenes (fast first, then reference)."""
    return Agreement(label, run_side(specs, fast), run_side(specs, reference))
