"""Thresholds of the belt OTS state sets and the transfer direction (Eq. 5.7–5.9).

All lengths are metres in the frame F_T (origin at the transport module's tip,
x towards the transfer unit), times are seconds since the OTS was formed.
Override single values with `dataclasses.replace`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, fields
from enum import Enum

from transfertwin._errors import InputError

__all__ = ["BeltThresholds", "TransferDirection"]


class TransferDirection(Enum):
    """Direction of a belt transfer."""

    TM_TO_TU = "tm_to_tu"  # forward: transport module -> transfer unit
    TU_TO_TM = "tu_to_tm"  # return: transfer unit -> transport module


@dataclass(frozen=True)
class BeltThresholds:
    """Thresholds of the belt state sets, metres and seconds in F_T (Eq. 5.7–5.9).

    Attributes:
        tm_x_min: Far end of the transport module's belts (Eq. 5.7).
        tm_x_max: The transport module's tip (Eq. 5.7).
        tu_x_min: Near end of the transfer unit's belts (Eq. 5.8).
        tu_x_max: Far end of the transfer unit's belts (Eq. 5.8).
        y_min: Right edge of the usable belt width.
        y_max: Left edge of the usable belt width.
        x_success: Success needs the box centre strictly beyond this x (Eq. 5.8).
        t_max: Timeout in seconds (Eq. 5.8 / 5.9).
        z_fall: Failure once the box bottom ``z - s_z`` is below this (extension);
            ``None`` disables the check.
        t0_tol: Tolerance of the pre-transfer time condition ``t = t0 = 0``.
        x_success_return: Success threshold of the return transfer (``x`` must
            be strictly below it); ``None`` mirrors ``x_success`` about
            ``tm_x_max``.
    """

    tm_x_min: float = -0.65
    tm_x_max: float = 0.0
    tu_x_min: float = 0.0
    tu_x_max: float = 0.5
    y_min: float = -0.2
    y_max: float = 0.2
    x_success: float = 0.2
    t_max: float = 30.0
    z_fall: float | None = -0.03
    t0_tol: float = 1e-9
    x_success_return: float | None = None

    def __post_init__(self) -> None:
        for field in fields(self):
            value = getattr(self, field.name)
            if value is None and field.name in ("z_fall", "x_success_return"):
                continue
            if isinstance(value, bool) or not isinstance(value, (int, float)):
                raise InputError(f"BeltThresholds.{field.name} must be a number, got {value!r}")
            if not math.isfinite(value):
                raise InputError(f"BeltThresholds.{field.name} must be finite, got {value}")
        if not self.tm_x_min < self.tm_x_max <= self.tu_x_min < self.tu_x_max:
            raise InputError("BeltThresholds: need tm_x_min < tm_x_max <= tu_x_min < tu_x_max")
        if not self.y_min < self.y_max:
            raise InputError("BeltThresholds: need y_min < y_max")
        if not self.tm_x_max <= self.x_success < self.tu_x_max:
            raise InputError("BeltThresholds: need tm_x_max <= x_success < tu_x_max (Eq. 5.8)")
        if not self.tm_x_min < self.success_threshold(TransferDirection.TU_TO_TM):
            raise InputError("BeltThresholds: the return success threshold must exceed tm_x_min")
        if self.t_max <= 0.0 or self.t0_tol < 0.0:
            raise InputError("BeltThresholds: need t_max > 0 and t0_tol >= 0")

    def success_threshold(self, direction: TransferDirection) -> float:
        """The x threshold of the success set for ``direction``, metres."""
        if direction is TransferDirection.TM_TO_TU:
            return float(self.x_success)
        if self.x_success_return is not None:
            return float(self.x_success_return)
        return 2.0 * self.tm_x_max - self.x_success
