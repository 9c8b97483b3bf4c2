"""A docked virtual unit seen from the module that simulates it (`MirroredUnitHAL`): belt
commands go to the unit over OPC UA and into the module's simulation; the simulated light
barriers are written to the unit, so a virtual unit looks on the wire as a physical one does.
"""

from __future__ import annotations

import asyncio

from asyncua import ua

__all__ = ["MirroredUnitHAL"]


class MirroredUnitHAL:
    """A remote virtual unit's HAL whose physics runs here.

    Belt commands go to the unit (it records and publishes them) and into the local
    simulation; the light barriers are read from the simulation and written to the unit
    when they change (a virtual unit's sensors are synchronised by the environment that
    simulates it).

    Args:
        remote: `OpcUaUnitHAL` of the unit.
        local: The simulated unit's HAL (`VirtualTransferSystem.tu`).
        loop: The event loop that owns the unit's session.
    """

    def __init__(self, remote, local, loop: asyncio.AbstractEventLoop) -> None:
        self.name = remote.name
        self._remote, self._local, self._loop = remote, local, loop
        self._published: dict[str, bool] | None = None

    def set_belt_speed(self, belt: str, speed_m_s: float) -> None:
        self._remote.set_belt_speed(belt, speed_m_s)
        self._local.set_belt_speed(belt, speed_m_s)

    def belt_speed(self, belt: str) -> float:
        return self._local.belt_speed(belt)

    def barriers(self) -> dict[str, bool]:
        now = self._local.barriers()
        if now != self._published:
            self._remote_write(now)
            self._published = dict(now)
        return now

    def _remote_write(self, barriers: dict[str, bool]) -> None:
        client = self._remote._client

        async def write() -> None:
            await client.write("OperationalData", "BarrierNearInterrupted", barriers["near"])
            await client.write("OperationalData", "BarrierFarInterrupted", barriers["far"])

        try:
            asyncio.run_coroutine_threadsafe(write(), self._loop).result(10)
        except ua.UaStatusCodeError as exc:  # a unit on real hardware reads its own barriers
            if exc.code not in (ua.StatusCodes.BadUserAccessDenied, ua.StatusCodes.BadNotWritable):
                raise
            self._remote_write = lambda barriers: None  # type: ignore[method-assign]


