"""Asset control software shared by physical assets and virtual models (behind a HAL)."""

from transfertwin.control._controller import (
    STALL_MODES,
    OTSController,
    TransferRecord,
    belts_for,
)
from transfertwin.control._hal import Clock, ObjectSensor, UnitHAL

__all__ = [
    "STALL_MODES",
    "Clock",
    "OTSController",
    "ObjectSensor",
    "TransferRecord",
    "UnitHAL",
    "belts_for",
]
