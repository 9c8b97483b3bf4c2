"""Reading docking-error tables and models, and choosing a study's docking-error model."""

from __future__ import annotations

import csv
import json
from pathlib import Path

import numpy as np

from transfertwin._errors import InputError
from transfertwin.data import calibration_csv_path
from transfertwin.study.docking._copula import (
    MIN_ROWS,
    GaussianCopula,
    PerStationCopula,
    copula_from_dict,
)
from transfertwin.study.docking._models import (
    DockingErrorModel,
    ResampledDockingErrors,
    docking_model_from_dict,
    measured_docking_errors,
)

__all__ = [
    "DOCKING_MODEL_KINDS",
    "STATION_COLUMN",
    "docking_model",
    "load_docking_model",
    "read_docking_errors",
]

#: The column naming a row's transfer unit (station) in real-experiment tables.
STATION_COLUMN = "transfer_unit"

#: Built-in choices of `docking_model` besides a model file.
DOCKING_MODEL_KINDS = ("copula", "copula-per-station", "resample")


def read_docking_errors(
    path: str | Path | None, need_units: bool = False
) -> tuple[np.ndarray, tuple[str, ...] | None]:
    """Errors (n, 3) in mm, mm, deg and, if asked, the transfer unit of each row.

    Args:
        path: Real-experiment CSV; None reads the shipped calibration experiments.
        need_units: Also return the `transfer_unit` column (for per-station models).

    Raises:
        InputError: Unreadable file, missing columns, too few rows (< MIN_ROWS).
    """
    path = calibration_csv_path() if path is None else Path(path)
    try:
        errors = measured_docking_errors(path)
        units = None
        if need_units:
            with path.open(newline="") as fh:
                reader = csv.DictReader(fh)
                if STATION_COLUMN not in (reader.fieldnames or []):
                    raise InputError(
                        f"{path}: missing column {STATION_COLUMN} (needed per station)"
                    )
                units = tuple(row[STATION_COLUMN].strip() for row in reader)
    except UnicodeDecodeError:
        raise InputError(f"{path}: not a UTF-8 text file") from None
    if len(errors) < MIN_ROWS:
        raise InputError(f"{path}: need at least {MIN_ROWS} rows, got {len(errors)}")
    if units is not None and not all(units):
        raise InputError(f"{path}: empty {STATION_COLUMN} in some rows")
    return errors, units


def load_docking_model(path: str | Path) -> GaussianCopula | PerStationCopula:
    """A copula saved by `transfertwin docking fit` (JSON)."""
    try:
        desc = json.loads(Path(path).read_text())
    except OSError as exc:
        raise InputError(f"{path}: cannot read: {exc.strerror}") from None
    except UnicodeDecodeError:
        raise InputError(f"{path}: not a UTF-8 text file") from None
    except json.JSONDecodeError as exc:
        raise InputError(f"{path}: not valid JSON: {exc.msg} (line {exc.lineno})") from None
    return copula_from_dict(desc)


def docking_model(kind: str, csv_path: str | Path | None = None) -> DockingErrorModel:
    """A study's docking-error model.

    Args:
        kind: 'copula' (fitted to `csv_path`), 'copula-per-station', 'resample' (the measured
            errors drawn with replacement) or the path of a model JSON (any model that
            `docking_model_from_dict` reads).
        csv_path: Measured docking errors; None: the shipped calibration experiments.
    """
    if kind == "resample":
        return ResampledDockingErrors.from_csv(csv_path)
    if kind == "copula":
        return GaussianCopula.fit(measured_docking_errors(csv_path))
    if kind == "copula-per-station":
        errors, units = read_docking_errors(csv_path, need_units=True)
        return PerStationCopula.fit(errors, units)
    path = Path(kind)
    if path.suffix.lower() != ".json" or not path.is_file():
        raise InputError(
            f"docking model {kind!r}: expected {', '.join(DOCKING_MODEL_KINDS)} "
            "or a model JSON written by 'transfertwin docking fit'"
        )
    try:
        desc = json.loads(path.read_text())
    except (OSError, ValueError) as exc:
        raise InputError(f"{kind}: cannot read docking model: {exc}") from None
    return docking_model_from_dict(desc)
