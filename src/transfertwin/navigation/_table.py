"""Emergent docking errors as a table: dock, measure with the ChArUco rig, one row per run,
with the same column names and units as the real experiments (Sec. 6.1.2, 6.3).

The measured columns (`dock_err_*`) are what the camera measures (Eq. 6.11); the true error of
the simulation sits beside them (`true_err_*`). The measurement renders with grey-level noise
σ = 2 (of 255) from its own generator, seeded by (seed, station, run).
"""

from __future__ import annotations

import csv
import io
import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, replace

import numpy as np

from transfertwin.navigation._charuco import CharucoRig
from transfertwin.navigation._docking import DockingConfig, DockingRun, simulate_docking
from transfertwin.navigation._floor import ShopFloor
from transfertwin.store import DOCKING_ERROR_COLUMNS

__all__ = ["TABLE_COLUMNS", "DockingRecord", "emergent_docking_errors", "records_csv"]

TABLE_COLUMNS = (
    "transfer_unit",
    "run",
    "seed",
    "status",
    *DOCKING_ERROR_COLUMNS,
    "true_err_x_mm",
    "true_err_y_mm",
    "true_err_theta_deg",
)

_SCALE = np.array([1000.0, 1000.0, 180.0 / math.pi])


@dataclass(frozen=True)
class DockingRecord:
    """One row: the run, its status, measured ξ̃ (mm, mm, deg; NaN if the board was not
    found) and true ξ (mm, mm, deg)."""

    transfer_unit: str
    run: int
    seed: int
    status: str
    measured: tuple[float, float, float]
    true: tuple[float, float, float]


def _measure(run: DockingRun, rig: CharucoRig, seed: int, index: int) -> tuple[str, np.ndarray]:
    rng = np.random.default_rng(np.random.SeedSequence([seed, index, run.run, 1]))
    xi = rig.measure_error(run.error, rng)
    if xi is None:
        return "board_not_found", np.full(3, np.nan)
    return run.status, xi * _SCALE


def emergent_docking_errors(
    floor: ShopFloor,
    stations: Sequence[str],
    runs: int,
    seed: int,
    cfg: DockingConfig | None = None,
    rig: CharucoRig | None = None,
    on_progress: Callable[[int, int], None] | None = None,
    keep: Callable[[DockingRun], None] | None = None,
) -> list[DockingRecord]:
    """`runs` docking runs per station, each measured by the ChArUco rig.

    Args:
        floor: The shop floor.
        stations: Station names ('A'..'D').
        runs: Runs per station.
        seed: Base seed; run r at station s uses SeedSequence([seed, index(s), r]).
        cfg: Robot, sensors and controller; None: the defaults.
        rig: Measurement rig; None: `CharucoRig(pixel_noise_sd=2.0)`.
        on_progress: Called with (done, total) after each run.
        keep: Called with each `DockingRun` (e.g. to draw the first one).
    """
    cfg = DockingConfig() if cfg is None else cfg
    rig = replace(CharucoRig(), pixel_noise_sd=2.0) if rig is None else rig
    total, out = runs * len(stations), []
    for name in stations:
        index = floor.station_names.index(floor.station(name).name)
        for r in range(runs):
            run = simulate_docking(floor, name, seed, r, cfg)
            if keep is not None:
                keep(run)
            status, measured = _measure(run, rig, seed, index)
            unit = floor.station(name).transfer_unit
            true = tuple(float(v) for v in run.error * _SCALE)
            out.append(
                DockingRecord(unit, r, seed, status, tuple(float(v) for v in measured), true)
            )
            if on_progress is not None:
                on_progress(len(out), total)
    return out


def records_csv(records: Sequence[DockingRecord]) -> str:
    """The rows as CSV text (columns `TABLE_COLUMNS`, six decimals)."""
    buf = io.StringIO()
    writer = csv.writer(buf, lineterminator="\n")
    writer.writerow(TABLE_COLUMNS)
    for rec in records:
        values = [f"{v:.6f}" for v in (*rec.measured, *rec.true)]
        writer.writerow([rec.transfer_unit, rec.run, rec.seed, rec.status, *values])
    return buf.getvalue()
