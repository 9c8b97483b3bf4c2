"""The Ray executor: a study's experiments as Ray tasks, on a local Ray or a cluster.

Experiments travel in chunks (one task runs a few experiments on one worker, which keeps
its compiled virtual systems between tasks); the driver keeps about two chunks per cluster
CPU in flight and hands each finished chunk to the caller, which is the store's only
writer. A task whose worker or node dies is run again by Ray (``max_retries``); a chunk's
rows come back only when the whole chunk is done, so a worker killed mid-chunk loses no
stored row and, since every row is keyed by (object, state, run) and the store inserts or
ignores by that key, no row is ever stored twice. Results do not depend on where a chunk
ran: every experiment carries its own seeds.

Ray is imported here only, when this executor starts: the local executor neither imports
nor starts Ray.
"""

from __future__ import annotations

import itertools
import logging
import socket
from collections.abc import Iterable, Iterator
from typing import Any

from transfertwin._errors import InputError
from transfertwin.study.experiment._experiment import ExperimentSpec, run_experiment

__all__ = ["RayExecutor", "run_chunk"]

Row = dict[str, object]

#: In-flight chunks per cluster CPU: one running, one queued so no CPU waits for the driver.
_IN_FLIGHT_PER_CPU = 2


def run_chunk(specs: list[ExperimentSpec]) -> list[Row]:
    """Task body: the result rows of a chunk of experiments, in the chunk's order."""
    return [run_experiment(spec).row() for spec in specs]


def _import_ray() -> Any:
    try:
        import ray
    except ImportError:
        raise InputError(
            "--executor ray needs Ray: pip install 'ray>=2.9' (or 'transfertwin[ray]')"
        ) from None
    return ray


def _host_port(address: str) -> tuple[str, int]:
    host, sep, port = address.rpartition(":")
    if not sep or not host or not port.isdigit() or not 0 < int(port) < 65536:
        raise InputError(f"--address expects auto or HOST:PORT, got {address!r}")
    return host.strip("[]"), int(port)


def _first_line(exc: BaseException) -> str:
    text = str(exc).strip()
    return text.splitlines()[0] if text else type(exc).__name__


class RayExecutor:
    """Runs experiment chunks as Ray tasks; use as a context manager (`start`/`close`).

    Args:
        address: None starts a private local Ray with `workers` CPUs (stopped on `close`);
            ``"auto"`` joins the cluster this machine belongs to; ``HOST:PORT`` joins the
            cluster whose head listens there (``ray start --head --port=PORT``).
        workers: CPUs of the local Ray (ignored when joining a cluster: its CPUs count).
        chunk_size: Experiments per task. Larger chunks cost less scheduling, smaller ones
            lose less work when a worker dies and balance better at the end of a study.
        max_retries: Times Ray re-runs a task whose worker or node died.
        connect_timeout_s: Time allowed to reach ``HOST:PORT`` before giving up.

    Raises:
        InputError: Ray is not installed, or a bad argument.
    """

    def __init__(
        self,
        address: str | None = None,
        *,
        workers: int = 1,
        chunk_size: int = 8,
        max_retries: int = 3,
        connect_timeout_s: float = 5.0,
    ) -> None:
        if workers < 1:
            raise InputError(f"workers must be at least 1, got {workers}")
        if chunk_size < 1:
            raise InputError(f"--chunk-size must be at least 1, got {chunk_size}")
        if max_retries < 0:
            raise InputError(f"max_retries must be >= 0, got {max_retries}")
        if address is not None and address != "auto":
            _host_port(address)
        _import_ray()  # fails fast, before any output exists
        self.address = address
        self.workers = workers
        self.chunk_size = chunk_size
        self.max_retries = max_retries
        self.connect_timeout_s = connect_timeout_s
        self.cpus = 0
        self._ray: Any = None
        self._task: Any = None

    def __repr__(self) -> str:
        where = self.address or f"local Ray, {self.workers} CPUs"
        return f"RayExecutor({where}, chunk_size={self.chunk_size})"

    def start(self) -> RayExecutor:
        """Start the local Ray or join the cluster.

        Raises:
            InputError: Ray is not installed or the cluster cannot be reached (one line).
        """
        if self._ray is not None:
            return self
        ray = _import_ray()
        if self.address not in (None, "auto"):
            # Ray itself retries an unreachable head for minutes; a plain TCP probe fails fast.
            host, port = _host_port(self.address)
            try:
                socket.create_connection((host, port), timeout=self.connect_timeout_s).close()
            except OSError as exc:
                raise InputError(
                    f"cannot reach a Ray cluster at {self.address}: {_first_line(exc)}"
                ) from None
        quiet = {"logging_level": logging.ERROR, "log_to_driver": False}
        try:
            if self.address is None:
                ray.init(num_cpus=self.workers, include_dashboard=False, **quiet)
            else:
                ray.init(address=self.address, **quiet)
        except Exception as exc:
            where = f"join the Ray cluster at {self.address}" if self.address else "start Ray"
            raise InputError(f"cannot {where}: {_first_line(exc)}") from None
        self._ray = ray
        self.cpus = max(1, int(ray.cluster_resources().get("CPU", 1)))
        self._task = ray.remote(num_cpus=1, max_retries=self.max_retries)(run_chunk)
        return self

    def batches(self, specs: Iterable[ExperimentSpec]) -> Iterator[list[Row]]:
        """Yield the rows of each chunk as it completes (chunks in completion order)."""
        if self._ray is None:
            raise RuntimeError("RayExecutor.start() first (or use it as a context manager)")
        ray, task = self._ray, self._task
        todo = iter(specs)
        chunks = iter(lambda: list(itertools.islice(todo, self.chunk_size)), [])
        pending = [task.remote(c) for c in itertools.islice(chunks, _IN_FLIGHT_PER_CPU * self.cpus)]
        try:
            while pending:
                done, pending = ray.wait(pending, num_returns=1)
                for ref in done:
                    yield ray.get(ref)
                    nxt = next(chunks, None)
                    if nxt is not None:
                        pending.append(task.remote(nxt))
        finally:
            for ref in pending:  # interrupted: nothing left running for this driver
                ray.cancel(ref, force=True)

    def close(self) -> None:
        """Leave the cluster (and stop the local Ray); calling it again does nothing."""
        if self._ray is not None:
            self._ray.shutdown()
            self._ray = self._task = None

    def __enter__(self) -> RayExecutor:
        return self.start()

    def __exit__(self, *exc: object) -> None:
        self.close()
