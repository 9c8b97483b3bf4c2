"""Rehearsal of the whole calibrate → predict → validate loop on an emulated plant (issue 12).

`rehearse` drives an `transfertwin.plant.EmulatedPlant` (the physical side) and the twin
(`transfertwin.study`): the twin's only input from the plant is the rows of its experiments.
"""

from transfertwin.rehearsal._rehearse import (
    REHEARSAL_KEYS,
    RehearsalConfig,
    calibration_design,
    holdout_split,
    parse_object_list,
    rehearse,
)

__all__ = [
    "REHEARSAL_KEYS",
    "RehearsalConfig",
    "calibration_design",
    "holdout_split",
    "parse_object_list",
    "rehearse",
]
