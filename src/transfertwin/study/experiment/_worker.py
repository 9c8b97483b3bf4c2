"""What a spawned worker process runs: its initializer and its entry point.

A worker unpickles these by module, so this module imports only the experiment itself
(`_experiment`: the engine, the object and the sets), not the runner's plan and docking
models: with the package's lazy surface (`transfertwin._lazy`) a worker starts without the
statistics, calibration and analysis modules (docs/speed.md, "Worker start-up").
"""

from __future__ import annotations

import os
import threading
import time

from transfertwin.study.experiment._experiment import ExperimentSpec, run_experiment

__all__ = ["exit_with_parent", "run_row", "warm_up"]


def exit_with_parent(parent_pid: int, period_s: float = 0.5) -> None:
    """Worker initializer: a daemon thread that ends this worker once its parent is gone
    (e.g. killed with SIGKILL, which runs no clean-up), so no orphan keeps computing."""

    def watch() -> None:
        while os.getppid() == parent_pid:
            time.sleep(period_s)
        os._exit(1)

    threading.Thread(target=watch, name="parent-watch", daemon=True).start()


def run_row(spec: ExperimentSpec) -> dict[str, object]:
    """Worker entry point: one experiment → one result row."""
    return run_experiment(spec).row()


def warm_up() -> int:
    """A first task for a new worker: its imports are done by the time it answers (the
    engine is imported with this module); returns the worker's pid."""
    return os.getpid()
