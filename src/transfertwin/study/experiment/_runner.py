"""The study runner: execute a plan on local workers into a result store, resumably.

Each result is committed as soon as it arrives, keyed by (object, state, run), so an
interrupted or killed study loses at most the experiments in flight; running the same plan
on the same store again skips what is done. Workers are processes (``spawn``), each keeping
its compiled virtual systems between experiments; the parent is the store's only writer.
Another executor (e.g. `RayExecutor`, for a cluster) can run the experiments instead: it
hands back rows in batches and the parent still writes them.
"""

from __future__ import annotations

import itertools
import logging
import multiprocessing as mp
import os
import time
from collections import Counter, defaultdict
from collections.abc import Callable, Collection, Container, Iterable, Iterator
from concurrent.futures import ProcessPoolExecutor
from contextlib import closing
from dataclasses import dataclass
from typing import Protocol, TypeVar

from transfertwin._errors import InputError
from transfertwin.objects import load_object
from transfertwin.store import ResultStore
from transfertwin.study.experiment._experiment import ExperimentSpec
from transfertwin.study.experiment._plan import StudyPlan
from transfertwin.study.experiment._pool import stream
from transfertwin.study.experiment._worker import exit_with_parent, run_row

__all__ = [
    "Executor",
    "ObjectSummary",
    "StudyOutcome",
    "check_plan",
    "run_rows",
    "run_study",
    "run_tagged",
    "summarize",
]

log = logging.getLogger(__name__)

T = TypeVar("T")


class Executor(Protocol):
    """Runs experiments somewhere else than the local worker processes (e.g. `RayExecutor`)."""

    def batches(self, specs: Iterable[ExperimentSpec]) -> Iterator[list[dict[str, object]]]:
        """Yield the result rows of `specs` in batches, as they complete."""
        ...


@dataclass(frozen=True)
class ObjectSummary:
    """Per-object tally of stored results."""

    object_id: str
    done: int
    ok: int
    successes: int
    by_status: dict[str, int]

    @property
    def success_share(self) -> float:
        """Successes among valid ('ok') experiments."""
        return self.successes / self.ok if self.ok else float("nan")


@dataclass(frozen=True)
class StudyOutcome:
    """What a `run_study` call did."""

    planned: int
    already_done: int
    ran: int
    interrupted: bool
    seconds: float

    @property
    def rate(self) -> float:
        """Experiments per second in this call."""
        return self.ran / self.seconds if self.seconds > 0 else float("nan")


def summarize(rows: Iterable[dict[str, object]]) -> list[ObjectSummary]:
    """Tally result rows per object, in order of first appearance."""
    counts: dict[str, Counter] = defaultdict(Counter)
    wins: Counter = Counter()
    for r in rows:
        oid = str(r["object_id"])
        counts[oid][str(r["status"])] += 1
        if r["status"] == "ok" and r["success"] == 1:
            wins[oid] += 1
    return [
        ObjectSummary(oid, sum(c.values()), c["ok"], wins[oid], dict(c))
        for oid, c in counts.items()
    ]


def check_plan(plan: StudyPlan) -> dict[str, str]:
    """Load every object of `plan` (meshes, hulls, units) before anything is written.

    Returns:
        Object reference → object id.

    Raises:
        InputError: An unreadable or invalid mesh, or two objects with the same id.
    """
    object_ids = {ref: load_object(ref, units=plan.units).object_id for ref in plan.objects}
    if len(set(object_ids.values())) != len(object_ids):
        ids = ", ".join(sorted(object_ids.values()))
        raise InputError(f"two objects share an id ({ids}); rename the mesh files")
    return object_ids


class _Skip:
    """Keys done, or outside the requested ones."""

    def __init__(self, done: set[tuple], only: frozenset[tuple]) -> None:
        self.done, self.only = done, only

    def __contains__(self, key: object) -> bool:
        return key in self.done or key not in self.only


def _pending(
    plan: StudyPlan, done: set[tuple], only: Collection[tuple] | None = None
) -> tuple[int, Iterator[ExperimentSpec]]:
    object_ids = check_plan(plan)
    skip: Container[tuple] = done if only is None else _Skip(done, frozenset(only))
    todo = sum(1 for key in plan.keys(object_ids) if key not in skip)
    return todo, (spec for _, spec in plan.specs(object_ids, skip))


def run_rows(
    specs: Iterable[ExperimentSpec], workers: int, executor: Executor | None = None
) -> Iterator[dict[str, object]]:
    """Run experiments on `workers` processes (or on `executor`); yields result rows as they
    complete (unordered when workers > 1 or with an executor).

    At most a few experiments per worker are in flight, so an interrupted run loses little.
    A worker that dies (e.g. a crash inside the engine) raises `BrokenProcessPool` here
    instead of hanging the study.
    """
    if executor is not None:
        with closing(executor.batches(specs)) as batches:
            for batch in batches:
                yield from batch
        return
    for _, row in run_tagged(((None, s) for s in specs), workers):
        yield row


def run_tagged(
    items: Iterable[tuple[T, ExperimentSpec]], workers: int
) -> Iterator[tuple[T, dict[str, object]]]:
    """`run_rows` for (tag, spec) pairs: yields (tag, result row) as they complete, so a
    caller that runs the same experiment under several scenes in one pool can tell the
    results apart (the tag stays in this process)."""
    if workers <= 1:
        for tag, spec in items:
            yield tag, run_row(spec)
        return
    ctx = mp.get_context("spawn")
    with ProcessPoolExecutor(
        workers, mp_context=ctx, initializer=exit_with_parent, initargs=(os.getpid(),)
    ) as pool:
        try:
            yield from stream(pool, items, 3 * workers)
        except BaseException:
            pool.shutdown(wait=False, cancel_futures=True)
            raise


def run_study(
    plan: StudyPlan,
    store: ResultStore,
    *,
    workers: int = 1,
    max_experiments: int | None = None,
    on_result: Callable[[dict[str, object]], None] | None = None,
    on_progress: Callable[[int, int], None] | None = None,
    keys: Collection[tuple] | None = None,
    executor: Executor | None = None,
) -> StudyOutcome:
    """Run every experiment of `plan` not yet in `store` (or only those of `keys`).

    Args:
        plan: The study plan; stored on first use, and a different plan is refused.
        store: Result store (single writer: this process).
        workers: Worker processes; 1 runs in this process (unused with `executor`).
        max_experiments: Stop after this many new results (for partial runs/timing).
        on_result: Called with each stored row.
        on_progress: Called with (done, total) of this call's experiments, once before the
            first result and after each stored batch (each row, locally).
        keys: Run only the experiments with these store keys (object_id, face, conveyor,
            theta_deg, run) — a round of an adaptive study; keys outside the plan are
            ignored. Required for an adaptive plan, which `run_adaptive` drives.
        executor: Runs the experiments instead of local processes (e.g. a started
            `RayExecutor`); each batch it returns is stored in one transaction.

    Returns:
        Counts and timing; `interrupted` is True after Ctrl-C (results so far are kept).
    """
    if workers < 1:
        raise InputError(f"workers must be at least 1, got {workers}")
    if max_experiments is not None and max_experiments < 1:
        raise InputError(f"max_experiments must be at least 1, got {max_experiments}")
    if plan.sampling != "exhaustive" and keys is None:
        raise InputError(f"a {plan.sampling} plan runs in rounds: use run_adaptive")
    store.init_plan(plan.plan_hash, plan.to_json())
    done = store.done_keys()
    todo, specs = _pending(plan, done, keys)
    if max_experiments is not None:
        todo = min(todo, max_experiments)
        specs = itertools.islice(specs, todo)
    report = on_progress or (lambda done, total: None)
    ran, interrupted = 0, False
    t0 = time.perf_counter()
    report(0, todo)
    batches = executor.batches(specs) if executor else ([row] for row in run_rows(specs, workers))
    try:
        with closing(batches):  # type: ignore[arg-type]
            for batch in batches:
                ran += store.put(batch)
                if on_result is not None:
                    for row in batch:
                        on_result(row)
                report(ran, todo)
    except KeyboardInterrupt:
        interrupted = True
    return StudyOutcome(plan.n_experiments, len(done), ran, interrupted, time.perf_counter() - t0)
