"""A short demo of single virtual transfers.

Runs one object through pre-transfer states every `step_deg` degrees on both faces (and the
single-belt states where they exist), with the docking error of a real calibration
experiment, and writes the results as CSV.
"""

from __future__ import annotations

import csv
from collections.abc import Callable
from pathlib import Path

from transfertwin.data import calibration_csv_path
from transfertwin.ots import experiment_states, filter_theta_step
from transfertwin.sim import DockingError
from transfertwin.store import DOCKING_ERROR_COLUMNS, export_results
from transfertwin.study.experiment._experiment import (
    ExperimentResult,
    ExperimentSpec,
    run_experiment,
)

__all__ = ["real_docking_error", "run_demo"]


def real_docking_error(experiment_id: int = 0) -> DockingError:
    """The measured docking error of one shipped real calibration experiment."""
    with calibration_csv_path().open() as fh:
        for row in csv.DictReader(fh):
            if int(row["experiment_id"]) == experiment_id:
                return DockingError.from_mm_deg(*(float(row[c]) for c in DOCKING_ERROR_COLUMNS))
    raise KeyError(experiment_id)


def run_demo(
    out_dir: Path,
    *,
    object_ref: str = "o1",
    step_deg: int = 45,
    on_progress: Callable[[int, int], None] | None = None,
) -> tuple[list[ExperimentResult], Path]:
    """Run the demo; returns the results and the path of the results CSV.

    Args:
        out_dir: Where ``results.csv`` is written (created if needed).
        object_ref: Built-in core id or mesh path.
        step_deg: Keep the states whose θ is a multiple of this.
        on_progress: Called with (done, total) after each experiment.
    """
    error = real_docking_error(0)
    states = filter_theta_step(experiment_states(), step_deg)
    results = []
    for i, s in enumerate(states, start=1):
        spec = ExperimentSpec(object_ref, s.face, s.conveyor, s.theta_deg, docking_error=error)
        results.append(run_experiment(spec))
        if on_progress is not None:
            on_progress(i, len(states))
    out_dir.mkdir(parents=True, exist_ok=True)
    return results, export_results([r.row() for r in results], out_dir / "results.csv")
