"""Package data: the real calibration experiments, the built-in cores, the ontology."""

from __future__ import annotations

from importlib import resources
from pathlib import Path

__all__ = ["CALIBRATION_CSV", "calibration_csv_path"]

CALIBRATION_CSV = "calibration_experiments.csv"


def calibration_csv_path() -> Path:
    """Path of the shipped copy of the study's 191 real calibration experiments."""
    return Path(str(resources.files(__name__).joinpath(CALIBRATION_CSV)))
