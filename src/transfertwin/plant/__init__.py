"""An emulated physical plant with hidden ground truth.

`EmulatedPlant(seed)` stands in for the real transfer system: it runs experiments E^P in a
simulation whose parameters the twin never sees and returns rows like the real calibration
table (`PLANT_COLUMNS`). The package sits above `transfertwin.study` in the layering, so no
calibration, study or validation code can import it; `transfertwin.rehearsal` drives both.
`reveal_truth` hands the hidden values to what scores a rehearsal afterwards (its report).
"""

from transfertwin.plant._mismatch import MISMATCH_PARTS, PLANT_KINDS, check_mismatch_off
from transfertwin.plant._physics import (
    CAMERA_FREE_KINDS,
    FLOOR_PLANT_KINDS,
    PlantPhysics,
    check_camera,
)
from transfertwin.plant._plant import PLANT_COLUMNS, EmulatedPlant, MassReading, PlantRequest
from transfertwin.plant._recording import CAMERA_RESOLUTION, PlantRecording
from transfertwin.plant._reveal import HiddenObject, HiddenScene, PlantTruth, reveal_truth
from transfertwin.plant._secret import PLANT_SEED_FILE, read_plant_seed, write_plant_seed

__all__ = [
    "CAMERA_FREE_KINDS",
    "CAMERA_RESOLUTION",
    "FLOOR_PLANT_KINDS",
    "MISMATCH_PARTS",
    "PLANT_COLUMNS",
    "PLANT_KINDS",
    "PLANT_SEED_FILE",
    "EmulatedPlant",
    "HiddenObject",
    "HiddenScene",
    "MassReading",
    "PlantPhysics",
    "PlantRecording",
    "PlantRequest",
    "PlantTruth",
    "check_camera",
    "check_mismatch_off",
    "read_plant_seed",
    "reveal_truth",
    "write_plant_seed",
]
