"""Docking-error models for studies: where each experiment's ξ comes from (Sec. 6.4).

A model draws one docking error from an explicit seed, so a study's errors are a pure
function of its plan. Two implementations here: resampling the real measured errors that
ship with the package, and one fixed error. The Gaussian copula of the calibration work
implements the same protocol.
"""

from __future__ import annotations

import csv
from dataclasses import dataclass, field
from pathlib import Path
from typing import Protocol, runtime_checkable

import numpy as np

from transfertwin._errors import InputError
from transfertwin.data import CALIBRATION_CSV, calibration_csv_path
from transfertwin.sim import DockingError
from transfertwin.store import DOCKING_ERROR_COLUMNS
from transfertwin.study.docking._copula import COPULA_KINDS, copula_from_dict

__all__ = [
    "DockingErrorModel",
    "FixedDockingError",
    "ResampledDockingErrors",
    "docking_model_from_dict",
    "measured_docking_errors",
]

_COLUMNS = DOCKING_ERROR_COLUMNS


@runtime_checkable
class DockingErrorModel(Protocol):
    """Draws docking errors; `describe()` round-trips through `docking_model_from_dict`."""

    def sample(self, seed: int) -> DockingError:
        """One docking error, a pure function of `seed`."""
        ...

    def describe(self) -> dict[str, object]:
        """JSON-able description (kind and parameters)."""
        ...


@dataclass(frozen=True)
class FixedDockingError:
    """Every experiment gets the same docking error."""

    error: DockingError = field(default_factory=DockingError)

    def sample(self, seed: int) -> DockingError:
        """The fixed error, whatever the seed."""
        return self.error

    def describe(self) -> dict[str, object]:
        """{'kind': 'fixed', 'x_mm', 'y_mm', 'theta_deg'}."""
        x, y, t = self.error.as_mm_deg()
        return {"kind": "fixed", "x_mm": x, "y_mm": y, "theta_deg": t}


def measured_docking_errors(path: str | Path | None = None) -> np.ndarray:
    """Measured docking errors (N, 3) in mm, mm, deg from a real-experiment CSV.

    Args:
        path: CSV with the columns dock_err_x_mm, dock_err_y_mm, dock_err_theta_deg;
            None reads the study's calibration experiments shipped with the package.
    """
    if path is None:
        text = calibration_csv_path().read_text()
        name = CALIBRATION_CSV
    else:
        try:
            text = Path(path).read_text()
        except OSError as exc:
            raise InputError(f"{path}: cannot read: {exc.strerror}") from None
        name = str(path)
    reader = csv.DictReader(text.splitlines())
    missing = [c for c in _COLUMNS if c not in (reader.fieldnames or [])]
    if missing:
        raise InputError(f"{name}: missing column(s) {', '.join(missing)}")
    try:
        rows = [[float(r[c]) for c in _COLUMNS] for r in reader]
    except ValueError as exc:
        raise InputError(f"{name}: non-numeric docking error: {exc}") from None
    if not rows:
        raise InputError(f"{name}: no docking errors")
    return np.asarray(rows, dtype=float)


@dataclass(frozen=True)
class ResampledDockingErrors:
    """Draw one of the measured docking errors uniformly (bootstrap of the real data).

    Attributes:
        errors_mm_deg: Measured errors as rows (x_mm, y_mm, theta_deg).
        source: Where they came from (for the plan description).
    """

    errors_mm_deg: tuple[tuple[float, float, float], ...]
    source: str = "builtin:calibration_experiments.csv"

    @classmethod
    def from_csv(cls, path: str | Path | None = None) -> ResampledDockingErrors:
        """Load measured errors from a CSV (None: the shipped calibration data)."""
        arr = measured_docking_errors(path)
        source = "builtin:calibration_experiments.csv" if path is None else str(path)
        return cls(tuple(tuple(float(v) for v in row) for row in arr), source)

    def sample(self, seed: int) -> DockingError:
        """One of the measured errors, chosen by `seed`."""
        i = int(np.random.default_rng(seed).integers(len(self.errors_mm_deg)))
        return DockingError.from_mm_deg(*self.errors_mm_deg[i])

    def describe(self) -> dict[str, object]:
        """{'kind': 'resample', 'source', 'n'}."""
        return {"kind": "resample", "source": self.source, "n": len(self.errors_mm_deg)}


def docking_model_from_dict(desc: dict[str, object]) -> DockingErrorModel:
    """Rebuild a model from `describe()` output."""
    kind = desc.get("kind")
    if kind == "fixed":
        return FixedDockingError(
            DockingError.from_mm_deg(
                float(desc["x_mm"]), float(desc["y_mm"]), float(desc["theta_deg"])
            )
        )
    if kind in COPULA_KINDS:
        return copula_from_dict(desc)
    if kind == "resample":
        source = str(desc.get("source", ""))
        path = None if source.startswith("builtin:") else source
        return ResampledDockingErrors.from_csv(path)
    raise InputError(f"unknown docking-error model kind {kind!r}")
