"""The adaptive study: rounds of `ObjectSampler` decisions, each round run by `run_study`.

The driver keeps no state of its own. Each call reads the stored results, replays the
samplers' rounds from the first (a decision uses only the runs it asked for, so replaying
reproduces it), and runs whatever a round still lacks through `run_study(..., keys=...)`
— the same runner, executor and idempotent store keys as an exhaustive study. An
interrupted study therefore resumes where it stopped, never runs a key twice, and ends with
the rows an uninterrupted run with the same seed would have stored.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass

from transfertwin._errors import InputError
from transfertwin.store import ResultStore
from transfertwin.study.adaptive._policy import AdaptivePolicy
from transfertwin.study.adaptive._sampler import ObjectSampler, StateKey
from transfertwin.study.experiment import StudyPlan, check_plan, run_study

__all__ = ["AdaptiveOutcome", "adaptive_policy", "run_adaptive"]


def adaptive_policy(plan: StudyPlan) -> AdaptivePolicy:
    """The adaptive settings stored in `plan`.

    Raises:
        InputError: The plan is not adaptive, or a setting is invalid.
    """
    if plan.sampling != "adaptive":
        raise InputError(f"the plan samples {plan.sampling!r}, not 'adaptive'")
    return AdaptivePolicy.from_dict(dict(plan.sampling_options))


@dataclass(frozen=True)
class AdaptiveOutcome:
    """What a `run_adaptive` call did.

    Attributes:
        planned: Runs of the exhaustive plan (the most the adaptive study can use).
        already_done: Results stored before this call.
        ran: New results stored by this call.
        interrupted: Ctrl-C (results so far are kept).
        seconds: Wall time of this call.
        finished: Every object's best and worst race is over.
        runs: Runs the samplers have asked for so far (stored when finished).
        rounds: Decisions taken, summed over objects.
        races: Per object id, how its best and worst race stand: "separated", "budget" or
            None (still running).
    """

    planned: int
    already_done: int
    ran: int
    interrupted: bool
    seconds: float
    finished: bool
    runs: int
    rounds: int
    races: dict[str, dict[str, str | None]]

    @property
    def rate(self) -> float:
        """Experiments per second in this call."""
        return self.ran / self.seconds if self.seconds > 0 else float("nan")

    @property
    def fraction(self) -> float:
        """Runs asked for as a share of the exhaustive plan."""
        return self.runs / self.planned if self.planned else float("nan")


def _outcome(row: dict[str, object]) -> int | None:
    return int(row["success"]) if row["status"] == "ok" else None  # type: ignore[arg-type]


def run_adaptive(
    plan: StudyPlan,
    store: ResultStore,
    *,
    workers: int = 1,
    max_experiments: int | None = None,
    on_progress: Callable[[int, int], None] | None = None,
    on_round: Callable[[int, int, int], None] | None = None,
    **run_kwargs: object,
) -> AdaptiveOutcome:
    """Run (or resume) an adaptive study of `plan` into `store`.

    Args:
        plan: A plan with ``sampling == "adaptive"``; ``plan.runs`` caps runs per state.
        store: Result store (single writer: this process).
        workers: Worker processes for each round (`run_study`).
        max_experiments: Stop after this many new results.
        on_progress: Called with (done, total) of this call's experiments so far; the total
            grows round by round.
        on_round: Called after each round with (round, objects still running, runs so far).
        **run_kwargs: Passed on to `run_study` (e.g. an executor).

    Returns:
        Counts, timing and how the races stand.
    """
    policy = adaptive_policy(plan)
    if max_experiments is not None and max_experiments < 1:
        raise InputError(f"max_experiments must be at least 1, got {max_experiments}")
    store.init_plan(plan.plan_hash, plan.to_json())
    object_ids = check_plan(plan)
    states: list[StateKey] = [(s.face, s.conveyor, s.theta_deg) for s in plan.states()]
    samplers = {oid: ObjectSampler(oid, states, plan.runs, policy) for oid in object_ids.values()}
    seen: dict[str, dict[StateKey, dict[int, int | None]]] = {oid: {} for oid in samplers}

    def record(row: dict[str, object]) -> None:
        by_state = seen.get(str(row["object_id"]))
        if by_state is not None:
            state = (str(row["face"]), str(row["conveyor"]), int(row["theta_deg"]))  # type: ignore[arg-type]
            by_state.setdefault(state, {})[int(row["run"])] = _outcome(row)  # type: ignore[arg-type]

    already = 0
    for row in store.rows():
        record(row)
        already += 1
    report = on_progress or (lambda done, total: None)
    ran, total, rounds, interrupted = 0, 0, 0, False
    t0 = time.perf_counter()
    report(0, 0)
    while True:
        active = [s for s in samplers.values() if not s.done]
        if not active:
            break
        wanted = [
            (s.object_id, *state, run)
            for s in active
            for state, target in s.targets.items()
            for run in range(target)
            if run not in seen[s.object_id].get(state, {})
        ]
        if wanted:
            if max_experiments is not None and ran >= max_experiments:
                break
            before, total = ran, total + len(wanted)
            out = run_study(
                plan, store, workers=workers, keys=wanted, on_result=record,
                max_experiments=None if max_experiments is None else max_experiments - ran,
                on_progress=lambda d, _t, b=before, n=total: report(b + d, n), **run_kwargs,
            )  # fmt: skip
            ran += out.ran
            if out.interrupted:
                interrupted = True
                break
            if any(run not in seen[o].get((f, c, t), {}) for o, f, c, t, run in wanted):
                break  # stopped by max_experiments
        rounds += 1
        for s in active:
            s.step({state: _runs(seen[s.object_id].get(state, {})) for state in states})
        if on_round is not None:
            still = sum(not s.done for s in samplers.values())
            on_round(rounds, still, sum(s.runs for s in samplers.values()))
    return AdaptiveOutcome(
        planned=plan.n_experiments,
        already_done=already,
        ran=ran,
        interrupted=interrupted,
        seconds=time.perf_counter() - t0,
        finished=all(s.done for s in samplers.values()),
        runs=sum(s.runs for s in samplers.values()),
        rounds=sum(s.rounds for s in samplers.values()),
        races={oid: dict(s.outcome) for oid, s in samplers.items()},
    )


def _runs(by_run: dict[int, int | None]) -> list[int | None]:
    """Outcomes of runs 0, 1, … up to the first run not stored."""
    out: list[int | None] = []
    while len(out) in by_run:
        out.append(by_run[len(out)])
    return out
