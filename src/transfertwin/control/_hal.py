"""The hardware abstraction layer (HAL) shared by physical assets and virtual models.

The control code of a unit (belt logic, OTS controller) is written once against these
protocols (Fig. 3.3b of the study: only the lowest layer differs between a physical asset
and its virtual model). `transfertwin.sim` implements them with MuJoCo; a remote asset is
reached through an OPC UA implementation; a real deployment adds a hardware one.
"""

from __future__ import annotations

from typing import Protocol, runtime_checkable

import numpy as np

__all__ = ["Clock", "ObjectSensor", "UnitHAL"]


@runtime_checkable
class UnitHAL(Protocol):
    """Belt drives and light barriers of one unit (transport module or transfer unit).

    Attributes:
        name: The unit's name, e.g. 'tm' or 'tu'.
    """

    name: str

    def set_belt_speed(self, belt: str, speed_m_s: float) -> None:
        """Drive belt 'left' or 'right' at a surface speed (m/s) along the unit's x axis."""
        ...

    def belt_speed(self, belt: str) -> float:
        """Current commanded surface speed of a belt (m/s)."""
        ...

    def barriers(self) -> dict[str, bool]:
        """Interruption of the light barriers on the unit's outer edges ('near', 'far')."""
        ...


@runtime_checkable
class Clock(Protocol):
    """Time source of a controller: wall time for a real asset, sim time for a model."""

    def now(self) -> float:
        """Seconds since `start`."""
        ...

    def start(self) -> None:
        """Set the time origin t_0 to now."""
        ...

    def wait(self, dt_s: float) -> None:
        """Let `dt_s` seconds pass."""
        ...


@runtime_checkable
class ObjectSensor(Protocol):
    """The vision system's state estimate of the object being transferred."""

    def observe(self) -> np.ndarray:
        """(a, x, y, z, s_x, s_y, s_z, θ) in F_T: possession code, AABB centre and half
        extents (m), yaw (rad). Shape (8,)."""
        ...
