"""Rehearsal of the whole calibrate → predict → validate loop on an emulated plant.

`rehearse` drives an `transfertwin.plant.EmulatedPlant` (the physical side) and the twin
(`transfertwin.study`): the twin's inputs from the plant are the rows of its experiments and
its mass readings (`EmulatedPlant.weigh`, the mass counter-measure). `run_operations`
measures the twin's predictions in operation (Sec. 7.2).
"""

from transfertwin.rehearsal._config import (
    COUNTER_MEASURES,
    FULLSTATE_SAMPLINGS,
    OBJECT_PRIORS,
    TWIN_FEATURE_SOLREF,
    RehearsalConfig,
    parse_ablations,
    parse_object_list,
    twin_scene,
)
from transfertwin.rehearsal._design import DESIGNS, calibration_design, holdout_split
from transfertwin.rehearsal._operations import (
    HANDLING_S,
    POLICIES,
    RECOVERY_S,
    best_station,
    docking_record,
    operation_summary,
    run_operations,
)
from transfertwin.rehearsal._rehearse import CURVE_KEYS, REHEARSAL_KEYS, curve_document, rehearse
from transfertwin.rehearsal._scoring import f05_intervals
from transfertwin.rehearsal._thresholded import majority_scores, training_threshold

__all__ = [
    "COUNTER_MEASURES",
    "CURVE_KEYS",
    "DESIGNS",
    "FULLSTATE_SAMPLINGS",
    "HANDLING_S",
    "OBJECT_PRIORS",
    "POLICIES",
    "RECOVERY_S",
    "REHEARSAL_KEYS",
    "TWIN_FEATURE_SOLREF",
    "RehearsalConfig",
    "best_station",
    "calibration_design",
    "curve_document",
    "docking_record",
    "f05_intervals",
    "holdout_split",
    "majority_scores",
    "operation_summary",
    "parse_ablations",
    "parse_object_list",
    "rehearse",
    "run_operations",
    "training_threshold",
    "twin_scene",
]
