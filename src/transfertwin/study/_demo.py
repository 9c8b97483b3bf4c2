"""The README's main job for now: a short demo of single virtual transfers.

Runs one object through pre-transfer states every `step_deg` degrees on both faces (and the
single-belt states where they exist), with the docking error of a real calibration
experiment, prints a table, writes the results as CSV and one image strip.
"""

from __future__ import annotations

import csv
from pathlib import Path

from rich.console import Console
from rich.progress import BarColumn, Progress, TextColumn, TimeRemainingColumn
from rich.table import Table

from transfertwin.data import calibration_csv_path
from transfertwin.ots import experiment_states, filter_theta_step
from transfertwin.sim import DockingError
from transfertwin.store import export_results
from transfertwin.study._experiment import ExperimentSpec, run_experiment

__all__ = ["real_docking_error", "run_demo"]


def real_docking_error(experiment_id: int = 0) -> DockingError:
    """The measured docking error of one shipped real calibration experiment."""
    with calibration_csv_path().open() as fh:
        for row in csv.DictReader(fh):
            if int(row["experiment_id"]) == experiment_id:
                return DockingError.from_mm_deg(
                    float(row["dock_err_x_mm"]),
                    float(row["dock_err_y_mm"]),
                    float(row["dock_err_theta_deg"]),
                )
    raise KeyError(experiment_id)


def run_demo(out_dir: Path, *, object_ref: str = "o1", step_deg: int = 45) -> Path:
    """Run the demo; returns the path of the results CSV."""
    console = Console()
    error = real_docking_error(0)
    states = filter_theta_step(experiment_states(), step_deg)
    results = []
    progress = Progress(
        TextColumn("{task.description}"), BarColumn(),
        TextColumn("{task.completed}/{task.total} {task.fields[rate]}"), TimeRemainingColumn(),
        console=console,
    )  # fmt: skip
    with progress:
        task = progress.add_task(f"E^V {object_ref}", total=len(states), rate="")
        for s in states:
            spec = ExperimentSpec(object_ref, s.face, s.conveyor, s.theta_deg, docking_error=error)
            results.append(run_experiment(spec))
            speed = progress.tasks[0].speed
            progress.update(task, advance=1, rate=f"{speed:.1f} exp/s" if speed else "")
    table = Table(title=f"{object_ref}: E^V with the docking error of real experiment 0")
    for col in ("face", "conveyor", "theta_deg", "status", "y1", "y2", "success", "t_end_s"):
        table.add_column(col)
    for r in results:
        table.add_row(r.face, r.conveyor, str(r.theta_deg), r.status, str(r.y1), str(r.y2),
                      str(r.success), f"{r.t_end_s:.2f}")  # fmt: skip
    console.print(table)
    ok = [r for r in results if r.status == "ok"]
    share = sum(r.success for r in ok) / len(ok) if ok else float("nan")
    console.print(f"success share over {len(ok)} valid states: {share:.2f}")
    out_dir.mkdir(parents=True, exist_ok=True)
    path = export_results([r.row() for r in results], out_dir / "results.csv")
    console.print(f"results: {path}")
    return path
