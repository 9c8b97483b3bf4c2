"""Local worker processes: the window of experiments in flight (`stream`) and a pool kept
warm between studies (`WarmPool`).

A study on local workers spawns its processes and each imports the engine and compiles its
object's model before its first experiment: seconds on a small machine, more than the
experiments of a small study take. A service that runs many small studies (the Experiment
Manager's on-the-fly predictions) keeps one `WarmPool` instead: its processes are started
and have imported the engine before the first request, and keep their compiled models
between requests (`system_for`'s cache).
"""

from __future__ import annotations

import itertools
import multiprocessing as mp
import os
from collections.abc import Iterable, Iterator
from concurrent.futures import FIRST_COMPLETED, Executor, Future, ProcessPoolExecutor, wait
from typing import TypeVar

from transfertwin._errors import InputError
from transfertwin.study.experiment._experiment import ExperimentSpec
from transfertwin.study.experiment._worker import exit_with_parent, run_row, warm_up

__all__ = ["WarmPool", "stream"]

T = TypeVar("T")


def stream(
    pool: Executor, items: Iterable[tuple[T, ExperimentSpec]], window: int
) -> Iterator[tuple[T, dict[str, object]]]:
    """Run (tag, spec) pairs on `pool`, at most `window` in flight (so an interrupted run
    loses little); yield (tag, result row) as they complete. On any exception the pending
    experiments are cancelled."""
    todo = iter(items)
    pending: dict[Future, T] = {
        pool.submit(run_row, s): tag for tag, s in itertools.islice(todo, window)
    }
    try:
        while pending:
            done, _ = wait(pending, return_when=FIRST_COMPLETED)
            for future in done:
                tag = pending.pop(future)
                yield tag, future.result()
                nxt = next(todo, None)
                if nxt is not None:
                    pending[pool.submit(run_row, nxt[1])] = nxt[0]
    except BaseException:
        for future in pending:
            future.cancel()
        raise


def _unusable(pool: ProcessPoolExecutor) -> bool:
    """Whether `pool` takes no more work: broken by a dead worker, or shut down."""
    return bool(getattr(pool, "_broken", False) or getattr(pool, "_shutdown_thread", False))


class WarmPool:
    """`workers` spawned processes kept between studies; an `Executor` of `run_study`
    (each result its own batch). Start it once (`start`: the processes are spawned and
    import the engine), use it for any number of studies, `close` it at the end.

    Results are those of the local workers (the same rows, bit for bit: an experiment's
    draws follow from its spec alone).
    """

    def __init__(self, workers: int = 2) -> None:
        if workers < 1:
            raise InputError(f"workers must be at least 1, got {workers}")
        self.workers = workers
        self._pool: ProcessPoolExecutor | None = None

    def __repr__(self) -> str:
        return f"WarmPool(workers={self.workers}, started={self._pool is not None})"

    def start(self) -> WarmPool:
        """Spawn the processes and wait until each has imported the engine; a pool that
        broke (a worker died) or was shut down is replaced by a new one."""
        if self._pool is not None and _unusable(self._pool):
            self._pool.shutdown(wait=False, cancel_futures=True)
            self._pool = None
        if self._pool is None:
            self._pool = ProcessPoolExecutor(
                self.workers, mp_context=mp.get_context("spawn"),
                initializer=exit_with_parent, initargs=(os.getpid(),),
            )  # fmt: skip
            for f in [self._pool.submit(warm_up) for _ in range(self.workers)]:
                f.result()
        return self

    def batches(self, specs: Iterable[ExperimentSpec]) -> Iterator[list[dict[str, object]]]:
        """Yield each experiment's row as a batch of one, as they complete."""
        pool = self.start()._pool
        assert pool is not None
        for _, row in stream(pool, ((None, s) for s in specs), 3 * self.workers):
            yield [row]

    def close(self) -> None:
        """End the processes (pending experiments are cancelled)."""
        if self._pool is not None:
            self._pool.shutdown(wait=True, cancel_futures=True)
            self._pool = None

    def __enter__(self) -> WarmPool:
        return self.start()

    def __exit__(self, *exc: object) -> None:
        self.close()
