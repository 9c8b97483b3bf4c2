"""The twin's predictions in operation (Sec. 6.6 put to use, Ch. 7): per pre-transfer
state of an object, its simulated success share with a Clopper–Pearson interval
(Eq. 6.26–6.27), ranked best first.

Two sources, in this order (docs/architecture.md, "Operation"):

1. a study store (`transfertwin study`, `./dev.sh run`): the states it simulated for the
   object;
2. on-the-fly virtual experiments of the Experiment Manager (`virtual_predictions`): the
   study's procedure for one object, every state of a coarse θ grid, a few runs each, with
   docking errors drawn from the fitted generator (Sec. 6.4).

The ranking is the success share, then the interval's lower bound (the better-supported
of two equal shares), then the study's state order, so it is deterministic.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from dataclasses import asdict, dataclass
from pathlib import Path

from transfertwin.cps.apps import docking_model

__all__ = [
    "DEFAULT_STATE",
    "ON_THE_FLY_THETA_STEP",
    "StatePrediction",
    "rank_states",
    "study_predictions",
    "virtual_predictions",
]

#: The state an object is loaded in without the twin (the demo's: front face, θ = 0).
DEFAULT_STATE = {"face": "front", "conveyor": "both", "theta_deg": 0}
#: θ grid of on-the-fly experiments: 28 states per object (the quick study's grid).
ON_THE_FLY_THETA_STEP = 30


@dataclass(frozen=True)
class StatePrediction:
    """One pre-transfer state's predicted success share (k of n runs, CP 95 % interval)."""

    face: str
    conveyor: str
    theta_deg: int
    n: int
    k: int
    share: float
    ci_low: float
    ci_high: float
    source: str

    def as_dict(self) -> dict[str, object]:
        return asdict(self)

    @property
    def state(self) -> dict[str, object]:
        """(face, conveyor, θ) as the module's load plan takes it."""
        return {"face": self.face, "conveyor": self.conveyor, "theta_deg": self.theta_deg}


def rank_states(
    rows: Iterable[Mapping[str, object]], obj: str, source: str
) -> list[StatePrediction]:
    """The states of `obj` in result rows (the store's columns), best first; states without
    a single 'ok' run are left out."""
    from transfertwin.study.fullstate import state_order, state_table

    mine = [r for r in rows if r.get("object_id") == obj]
    stats = [s for s in state_table(mine) if s.n > 0]
    out = [StatePrediction(s.face, s.conveyor, s.theta_deg, s.n, s.k, s.y_mean, s.ci_low,
                           s.ci_high, source) for s in stats]  # fmt: skip
    return sorted(out, key=lambda p: (-p.share, -p.ci_low,
                                      state_order((obj, p.face, p.conveyor, p.theta_deg))))


def study_predictions(store: str | Path, obj: str) -> list[StatePrediction]:
    """`obj`'s states in a study store, best first (empty: the store never simulated it)."""
    from transfertwin.store import SQLiteResultStore

    db = SQLiteResultStore(store, create=False)
    try:
        return rank_states(db.rows(), obj, f"study {Path(store).name}")
    finally:
        db.close()


def virtual_predictions(obj: str, runs: int, seed: int, scene=None,
                        workers: int = 1) -> list[StatePrediction]:  # fmt: skip
    """Run the study's procedure for `obj` now (every state of the `ON_THE_FLY_THETA_STEP`
    grid, `runs` runs each, docking errors from the fitted generator; in this process, or
    on `workers` worker processes); best first. Deterministic in `seed` (the same rows
    whatever `workers`)."""
    from transfertwin.store import MemoryResultStore
    from transfertwin.study.experiment import StudyPlan, run_study

    kwargs = {} if scene is None else {"scene": scene}
    plan = StudyPlan((obj,), ON_THE_FLY_THETA_STEP, runs, seed, docking_model(), **kwargs)
    store = MemoryResultStore()
    run_study(plan, store, workers=workers)
    return rank_states(store.rows(), obj, f"virtual experiments ({runs} runs per state)")
