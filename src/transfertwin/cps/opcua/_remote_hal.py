"""The HAL of a remote unit, reached through its OPC UA server (Fig. 3.3b).

The OTS controller is synchronous code that runs in a worker thread; this HAL turns its
calls into OPC UA calls on the event loop that owns the client session. A virtual unit and
a physical unit look the same through it.
"""

from __future__ import annotations

import asyncio
from typing import Any

from transfertwin.cps.opcua._client import AssetClient

__all__ = ["OpcUaUnitHAL"]

_SPEED = {"left": "BeltSpeedLeft", "right": "BeltSpeedRight"}


class OpcUaUnitHAL:
    """`transfertwin.control.UnitHAL` over an OPC UA session.

    Args:
        client: Session with the unit's server (operator role).
        loop: The event loop running that session.
        timeout_s: Limit for one remote call.
    """

    def __init__(
        self, client: AssetClient, loop: asyncio.AbstractEventLoop, timeout_s: float = 10.0
    ) -> None:
        self.name = client.asset_id
        self._client = client
        self._loop = loop
        self._timeout = timeout_s

    def _run(self, coro: Any) -> Any:
        return asyncio.run_coroutine_threadsafe(coro, self._loop).result(self._timeout)

    def set_belt_speed(self, belt: str, speed_m_s: float) -> None:
        """Call the unit's SetBeltSpeed operation."""
        if belt not in _SPEED:
            raise ValueError(f"unknown belt {belt!r}")
        ok = self._run(self._client.call("SetBeltSpeed", belt, float(speed_m_s)))
        if not ok:
            raise RuntimeError(f"{self.name} refused SetBeltSpeed({belt}, {speed_m_s})")

    def belt_speed(self, belt: str) -> float:
        """The unit's reported belt speed."""
        return float(self._run(self._client.read("OperationalData", _SPEED[belt])))

    def barriers(self) -> dict[str, bool]:
        """The unit's reported light barriers."""
        near = self._run(self._client.read("OperationalData", "BarrierNearInterrupted"))
        far = self._run(self._client.read("OperationalData", "BarrierFarInterrupted"))
        return {"near": bool(near), "far": bool(far)}
