"""Experiments and studies over the virtual transfer system (Ch. 6)."""

from transfertwin.study._docking_models import (
    DockingErrorModel,
    FixedDockingError,
    ResampledDockingErrors,
    docking_model_from_dict,
    measured_docking_errors,
)
from transfertwin.study._experiment import (
    RESULT_COLUMNS,
    ExperimentResult,
    ExperimentSpec,
    Frame,
    run_experiment,
    system_for,
)
from transfertwin.study._plan import PRESETS, Preset, StudyPlan, experiment_seeds, parse_objects
from transfertwin.study._profile import load_profile, save_profile, scene_from_dict, scene_to_dict
from transfertwin.study._runner import ObjectSummary, StudyOutcome, run_study, summarize

__all__ = [
    "PRESETS",
    "RESULT_COLUMNS",
    "DockingErrorModel",
    "ExperimentResult",
    "ExperimentSpec",
    "FixedDockingError",
    "Frame",
    "ObjectSummary",
    "Preset",
    "ResampledDockingErrors",
    "StudyOutcome",
    "StudyPlan",
    "docking_model_from_dict",
    "experiment_seeds",
    "load_profile",
    "measured_docking_errors",
    "parse_objects",
    "run_experiment",
    "run_study",
    "save_profile",
    "scene_from_dict",
    "scene_to_dict",
    "summarize",
    "system_for",
]
