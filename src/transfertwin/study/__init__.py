"""Experiments and studies over the virtual transfer system (Ch. 6)."""

from transfertwin.study._experiment import (
    RESULT_COLUMNS,
    ExperimentResult,
    ExperimentSpec,
    Frame,
    run_experiment,
    system_for,
)

__all__ = [
    "RESULT_COLUMNS",
    "ExperimentResult",
    "ExperimentSpec",
    "Frame",
    "run_experiment",
    "system_for",
]
