"""Emergent versus measured docking errors, per station: means, SDs and a two-sample
Kolmogorov–Smirnov test per component (scipy.stats.ks_2samp)."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from scipy import stats

from transfertwin.store import DOCKING_ERROR_COLUMNS
from transfertwin.study.docking import read_docking_errors

__all__ = ["ComponentComparison", "compare_with_real", "real_errors_by_unit"]


@dataclass(frozen=True)
class ComponentComparison:
    """One station and one error component (mm or deg).

    Attributes:
        transfer_unit: 'TU_A'...
        column: 'dock_err_x_mm', 'dock_err_y_mm' or 'dock_err_theta_deg'.
        n_sim, n_real: Sample sizes.
        mean_sim, sd_sim, mean_real, sd_real: Sample means and SDs (ddof = 1).
        ks_statistic, ks_pvalue: Two-sample KS test (NaN with fewer than 2 values on a side).
    """

    transfer_unit: str
    column: str
    n_sim: int
    n_real: int
    mean_sim: float
    sd_sim: float
    mean_real: float
    sd_real: float
    ks_statistic: float
    ks_pvalue: float


def real_errors_by_unit(path: str | Path | None = None) -> dict[str, np.ndarray]:
    """Measured errors (n, 3) in mm, mm, deg per transfer unit (None: the shipped table)."""
    errors, units = read_docking_errors(path, need_units=True)
    arr = np.asarray(units)
    return {u: errors[arr == u] for u in sorted(set(units))}


def _stats(v: np.ndarray) -> tuple[float, float]:
    """Mean and SD (ddof = 1); NaN where too few values."""
    mean = float(np.mean(v)) if len(v) else float("nan")
    return mean, float(np.std(v, ddof=1)) if len(v) > 1 else float("nan")


def compare_with_real(
    sim: np.ndarray,
    units: Sequence[str],
    real: dict[str, np.ndarray] | None = None,
) -> list[ComponentComparison]:
    """Per station and component: emergent (`sim`, (n, 3) mm, mm, deg) versus real.

    Args:
        sim: Emergent errors, rows (x_mm, y_mm, theta_deg).
        units: Transfer unit of each row ('TU_A'...).
        real: Measured errors per unit; None reads the shipped calibration experiments.
    """
    real = real_errors_by_unit() if real is None else real
    arr = np.asarray(units)
    out = []
    for unit in sorted(set(units)):
        s = np.asarray(sim)[arr == unit]
        r = real.get(unit, np.empty((0, 3)))
        for k, col in enumerate(DOCKING_ERROR_COLUMNS):
            if len(s) >= 2 and len(r) >= 2:
                ks = stats.ks_2samp(s[:, k], r[:, k])
                d, p = float(ks.statistic), float(ks.pvalue)
            else:
                d = p = float("nan")
            out.append(
                ComponentComparison(
                    unit, col, len(s), len(r), *_stats(s[:, k]), *_stats(r[:, k]), d, p
                )
            )
    return out
