"""The twin's predictions in operation (Sec. 6.6 put to use, Ch. 7): per pre-transfer
state of an object, its simulated success share with a Clopper–Pearson interval
(Eq. 6.26–6.27), ranked best first.

Two sources, in this order (docs/architecture.md, "Operation"):

1. a study store (`transfertwin study`, `./dev.sh run`): the states it simulated for the
   object;
2. on-the-fly virtual experiments of the Experiment Manager (`virtual_predictions`): the
   study's procedure for one object, every state of a coarse θ grid, a few runs each, with
   docking errors drawn from the fitted generator (Sec. 6.4).

What a prediction covers follows from the leg its experiments ran (`StudyPlan.leg`): an
``operation`` (the on-the-fly default) predicts both legs of a floor's transport operation
from the same runs — the pick-up's k_pickup of n, the delivery's k of k_pickup (tried only
after a pick-up succeeded) —; a ``round-trip`` store (the study's E^V, there and back from
the module) predicts the delivery only; a ``pick-up`` store the pick-up only.

The ranking is the success share, then the interval's lower bound (the better-supported
of two equal shares), then the study's state order, so it is deterministic.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping, Sequence
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

from transfertwin.cps.apps import DEFAULT_STATE, docking_model

__all__ = [
    "DEFAULT_STATE",
    "ON_THE_FLY_THETA_STEP",
    "StatePrediction",
    "campaign_advice",
    "campaign_predictions",
    "learning_alone_states",
    "rank_states",
    "study_predictions",
    "twin_words",
    "virtual_predictions",
]

#: θ grid of on-the-fly experiments: 28 states per object (the quick study's grid).
ON_THE_FLY_THETA_STEP = 30


def learning_alone_states() -> list[dict[str, object]]:
    """The states learning alone ranks (``[operation] twin = false``): the default state
    first (an object's first order is loaded as nearest-idle loads it), then every state
    of the `ON_THE_FLY_THETA_STEP` grid, each without a twin's prediction (`uninformed`)."""
    from transfertwin.cps.dispatch._learn import uninformed
    from transfertwin.ots import experiment_states, filter_theta_step

    grid = [{"face": s.face, "conveyor": s.conveyor, "theta_deg": s.theta_deg}
            for s in filter_theta_step(experiment_states(), ON_THE_FLY_THETA_STEP)]  # fmt: skip
    first = dict(DEFAULT_STATE)
    return uninformed([first, *(s for s in grid if s != first)])


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
    leg: str = "round-trip"
    k_pickup: int | None = None

    def as_dict(self) -> dict[str, object]:
        return asdict(self)

    @property
    def state(self) -> dict[str, object]:
        """(face, conveyor, θ) as the module's load plan takes it."""
        return {"face": self.face, "conveyor": self.conveyor, "theta_deg": self.theta_deg}


def rank_states(
    rows: Iterable[Mapping[str, object]], obj: str, source: str, leg: str = "round-trip"
) -> list[StatePrediction]:
    """The states of `obj` in result rows (the store's columns) of experiments that ran
    `leg`, best first by the share of runs in which every transfer succeeded; states
    without a single 'ok' run are left out. An 'operation' or 'pick-up' state also counts
    its successful pick-ups (y1) in ``k_pickup``."""
    from transfertwin.study.fullstate import state_order, state_table

    mine = [r for r in rows if r.get("object_id") == obj]
    stats = [s for s in state_table(mine) if s.n > 0]
    picked: dict[tuple[str, str, int], int] = {}
    if leg != "round-trip":
        for r in mine:
            if r.get("status") == "ok" and r.get("y1") == 1:
                key = (str(r["face"]), str(r["conveyor"]), int(r["theta_deg"]))
                picked[key] = picked.get(key, 0) + 1
    out = [StatePrediction(s.face, s.conveyor, s.theta_deg, s.n, s.k, s.y_mean, s.ci_low,
                           s.ci_high, source, leg,
                           picked.get((s.face, s.conveyor, s.theta_deg), 0)
                           if leg != "round-trip" else None)
           for s in stats]  # fmt: skip
    return sorted(
        out,
        key=lambda p: (-p.share, -p.ci_low, state_order((obj, p.face, p.conveyor, p.theta_deg))),
    )


def study_predictions(store: str | Path, obj: str) -> list[StatePrediction]:
    """`obj`'s states in a study store, best first (empty: the store never simulated it);
    the legs they predict are those of the store's plan."""
    import json

    from transfertwin.store import SQLiteResultStore

    db = SQLiteResultStore(store, create=False)
    try:
        plan = db.plan()
        leg = json.loads(plan.plan_json).get("leg", "round-trip") if plan else "round-trip"
        return rank_states(db.rows(), obj, f"study {Path(store).name}", leg)
    finally:
        db.close()


def _typed(row: Mapping[str, str]) -> dict[str, Any]:
    """A ``fullstate.csv`` row with the types the ranking reads."""
    out: dict[str, Any] = dict(row)
    out["theta_deg"] = int(row["theta_deg"])
    for key in ("success", "y1", "y2", "run"):
        value = row.get(key)
        out[key] = int(float(value)) if value not in (None, "", "None") else None
    return out


def _fullstate_rows(folder: str | Path) -> list[dict[str, Any]]:
    """A campaign's ``fullstate.csv`` rows, typed (`_typed`)."""
    import csv

    with (Path(folder) / "fullstate.csv").open(newline="") as f:
        return [_typed(r) for r in csv.DictReader(f)]


def campaign_predictions(folder: Path, objects: Sequence[str], campaign_id: str,
                         leg: str = "operation") -> dict[str, list[dict[str, Any]]]:  # fmt: skip
    """Each object's states as the calibrated twin predicts them (its ``fullstate.csv``),
    ranked best first as the TMS ranks them (`rank_states`), as `StatePrediction.as_dict`."""
    rows = _fullstate_rows(folder)
    source = f"campaign {campaign_id}"
    return {o: [p.as_dict() for p in rank_states(rows, o, source, leg)] for o in objects}


def campaign_advice(folder: str | Path, objects: Sequence[str]) -> dict[str, str]:
    """Each object's placement advice from a campaign's ``fullstate.csv``, decided as the
    study's report decides it (face, then conveyor, then θ, each only where the twin's runs
    tell them apart: `decide_placement`), in words; '' for an object it has no run of."""
    from transfertwin.study.fullstate import decide_placement, placement_headline, state_table

    stats = state_table(_fullstate_rows(folder))
    out = {}
    for obj in objects:
        mine = [s for s in stats if s.object_id == obj and s.n > 0]
        out[obj] = placement_headline(decide_placement(mine, obj)) if mine else ""
    return out


def virtual_predictions(obj: str, runs: int, seed: int, scene=None, workers: int = 1,
                        leg: str = "operation", executor=None,
                        sampling: str = "exhaustive") -> list[StatePrediction]:  # fmt: skip
    """Run the study's procedure for `obj` now (every state of the `ON_THE_FLY_THETA_STEP`
    grid, of `leg` — by default a floor's whole operation, so that both legs are
    predicted —, docking errors from the fitted generator; in this process, on `workers`
    worker processes, or on `executor`, e.g. a started `WarmPool`); best first.
    Deterministic in `seed` (the same rows whatever runs them).

    `sampling` ``"exhaustive"``: `runs` runs each state. ``"adaptive"``: bounded by the same
    number of experiments in all (states × `runs`), spent where they can change the best
    (and worst) state: a first round on every state, then rounds on the race's leaders and
    challengers (`transfertwin.study.adaptive.run_adaptive`, `adaptive_options`), up to
    `ADAPTIVE_MAX_FACTOR` × `runs` runs on a state; a race still open when the budget is
    spent ends there (the ranking then stands on the runs made)."""
    from transfertwin.cps.floor import SAMPLINGS
    from transfertwin.store import MemoryResultStore
    from transfertwin.study.adaptive import ADAPTIVE_MAX_FACTOR, adaptive_options
    from transfertwin.study.experiment import StudyPlan, run_study

    if sampling not in SAMPLINGS:
        raise ValueError(f"sampling must be one of {', '.join(SAMPLINGS)}, got {sampling!r}")
    adaptive = sampling == "adaptive"
    kwargs: dict[str, Any] = {} if scene is None else {"scene": scene}
    if adaptive:
        kwargs |= {"sampling": "adaptive", "sampling_options": adaptive_options(runs)}
    most = ADAPTIVE_MAX_FACTOR * runs if adaptive else runs
    plan = StudyPlan((obj,), ON_THE_FLY_THETA_STEP, most, seed, docking_model(), leg=leg,
                     **kwargs)  # fmt: skip
    store = MemoryResultStore()
    if adaptive:
        from transfertwin.study.adaptive import run_adaptive

        budget = len(plan.states()) * runs
        run_adaptive(plan, store, workers=workers, max_experiments=budget, executor=executor)
        source = f"adaptive virtual experiments ({store.count()} runs, at most {budget})"
    else:
        run_study(plan, store, workers=workers, executor=executor)
        source = f"virtual experiments ({runs} runs per state)"
    return rank_states(store.rows(), obj, source, leg)


def twin_words(pred: Mapping[str, object]) -> str:
    """What the twin predicted for a state, in words: per leg it simulated, k of n runs
    (a ranked state as `StatePrediction.as_dict` gives it)."""
    k, n, leg, picked = pred["k"], pred["n"], pred.get("leg", "round-trip"), pred.get("k_pickup")
    if leg == "operation" and picked is not None:
        said = f"picked up in {picked} of {n} runs, delivered in {k} of {picked}"
    elif leg == "pick-up":
        said = f"picked up in {k} of {n} runs"
    else:
        said = f"there and back in {k} of {n} runs"
    return f"twin: {said} ({pred['source']})"
