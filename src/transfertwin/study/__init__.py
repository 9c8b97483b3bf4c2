"""Experiments and studies over the virtual transfer system (Ch. 6)."""

from transfertwin.study._analysis import (
    AnalysisResult,
    SelectedState,
    Selection,
    SeriesStats,
    StateStat,
    analyze,
    select,
    series_table,
    state_table,
)
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
from transfertwin.study._intervals import Interval, clopper_pearson, clopper_pearson_array
from transfertwin.study._plan import PRESETS, Preset, StudyPlan, experiment_seeds, parse_objects
from transfertwin.study._profile import load_profile, save_profile, scene_from_dict, scene_to_dict
from transfertwin.study._runner import ObjectSummary, StudyOutcome, run_study, summarize
from transfertwin.study._selection import (
    CircularSeries,
    best_global,
    best_local,
    circular_moving_average,
    moving_average,
    worst_global,
    worst_local,
)

__all__ = [
    "PRESETS",
    "RESULT_COLUMNS",
    "AnalysisResult",
    "CircularSeries",
    "DockingErrorModel",
    "ExperimentResult",
    "ExperimentSpec",
    "FixedDockingError",
    "Frame",
    "Interval",
    "ObjectSummary",
    "Preset",
    "ResampledDockingErrors",
    "SelectedState",
    "Selection",
    "SeriesStats",
    "StateStat",
    "StudyOutcome",
    "StudyPlan",
    "analyze",
    "best_global",
    "best_local",
    "circular_moving_average",
    "clopper_pearson",
    "clopper_pearson_array",
    "docking_model_from_dict",
    "experiment_seeds",
    "load_profile",
    "measured_docking_errors",
    "moving_average",
    "parse_objects",
    "run_experiment",
    "run_study",
    "save_profile",
    "scene_from_dict",
    "scene_to_dict",
    "select",
    "series_table",
    "state_table",
    "summarize",
    "system_for",
    "worst_global",
    "worst_local",
]
