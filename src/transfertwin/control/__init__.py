"""Asset control software shared by physical assets and virtual models (behind a HAL)."""

from transfertwin.control._controller import OTSController, TransferRecord, belts_for
from transfertwin.control._hal import Clock, ObjectSensor, UnitHAL

__all__ = ["Clock", "OTSController", "ObjectSensor", "TransferRecord", "UnitHAL", "belts_for"]
