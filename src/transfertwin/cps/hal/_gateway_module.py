"""A transport module on real hardware, as its HAL gateway's nodes: drive commands, pose,
object sensing, belts and barriers (`ModuleGateway`), the wall clock the transfer loop runs
on there (`WallClock`), the gateway's belt pair as a thread-side HAL (`ThreadHAL`) and the
world such a module's process has instead of a simulation (`GatewayWorld`).
"""

from __future__ import annotations

import asyncio
import threading
import time
from typing import TYPE_CHECKING, Any

import numpy as np

from transfertwin.cps.hal._gateway import GatewayError, GatewayLink

if TYPE_CHECKING:
    from transfertwin.cps.floor import AssetConfig
    from transfertwin.sim import SceneConfig

__all__ = ["COMMAND_TIMEOUT_S", "GatewayWorld", "ModuleGateway", "ThreadHAL", "WallClock"]

#: How long a drive command may take at the gateway before the step fails, s.
COMMAND_TIMEOUT_S = 120.0


class ModuleGateway(GatewayLink):
    """A remote transport module's nodes at its HAL gateway (async)."""

    def __init__(self, cfg: AssetConfig) -> None:
        super().__init__(cfg)
        self._seq = time.time_ns() // 1_000_000 % 1_000_000_000  # fresh after a restart

    async def set_belt(self, belt: str, speed_m_s: float) -> None:
        """Command the module's `belt` ('left' or 'right')."""
        from asyncua import ua

        if belt not in ("left", "right"):
            raise ValueError(f"unknown belt {belt!r}")
        await self.write(f"belt_{belt}", float(speed_m_s), ua.VariantType.Double)

    async def barriers(self) -> dict[str, bool]:
        """The module's light barriers."""
        near, far = await self.read("barrier_near", "barrier_far")
        return {"near": bool(near), "far": bool(far)}

    async def pose(self) -> np.ndarray:
        """The module's pose (x m, y m, θ rad) as its localisation reports it."""
        return np.array([float(v) for v in await self.read("pose_x", "pose_y", "pose_theta")])

    async def object_state(self) -> np.ndarray | None:
        """What the module's object sensor sees: (8,) in F_T, None when nothing."""
        (value,) = await self.read("object_state")
        s = np.asarray(value, dtype=float)
        if s.shape != (8,):
            raise GatewayError(f"HAL gateway {self.endpoint}: object_state must hold 8 "
                               f"numbers, got {s.shape}")  # fmt: skip
        return None if np.isnan(s).all() else s

    async def command(self, verb: str, station: str = "",
                      timeout_s: float = COMMAND_TIMEOUT_S) -> tuple[bool, str]:  # fmt: skip
        """Have the module `verb` ('navigate', 'dock', 'undock') `station`; (done, why not)."""
        from asyncua import ua

        self._seq += 1
        seq = str(self._seq)
        await self.write("command", f"{seq} {verb} {station}".strip(), ua.VariantType.String)
        t0 = time.monotonic()
        poll = max(self.cfg.hal.poll_s, 0.01)
        while time.monotonic() - t0 < timeout_s:
            (state,) = await self.read("command_state")
            head, _, rest = str(state or "").partition(" ")
            if head == seq and rest == "done":
                return True, ""
            if head == seq and rest.startswith("failed"):
                return False, f"{verb} {station}: {rest.removeprefix('failed').lstrip(': ')}"
            await asyncio.sleep(poll)
        return False, f"{verb} {station}: no answer from the module within {timeout_s:.0f} s"


class WallClock:
    """`transfertwin.control.Clock` of a real machine: wall time, waits on a fixed grid
    (a late sample does not shift the ones after it). Time starts with the first wait
    after `start`, when the belts run: what is observed before it (the pre-transfer state
    of Eq. 5.7, t = 0) is at t0."""

    def __init__(self) -> None:
        self._t0: float | None = None
        self._next = 0.0

    def now(self) -> float:
        return 0.0 if self._t0 is None else time.monotonic() - self._t0

    def start(self) -> None:
        self._t0 = None

    def wait(self, dt_s: float) -> None:
        if self._t0 is None:
            self._t0 = self._next = time.monotonic()
        self._next += dt_s
        time.sleep(max(0.0, self._next - time.monotonic()))


class ThreadHAL:
    """The module's belts and barriers (`UnitHAL`) and its object sensor (`ObjectSensor`)
    for the controller's thread: each call a request on the loop that owns the session."""

    def __init__(self, name: str, gw: ModuleGateway, loop: asyncio.AbstractEventLoop) -> None:
        self.name, self._gw, self._loop = name, gw, loop
        self._speeds = {"left": 0.0, "right": 0.0}

    def _run(self, coro: Any) -> Any:
        return asyncio.run_coroutine_threadsafe(coro, self._loop).result(10.0)

    def set_belt_speed(self, belt: str, speed_m_s: float) -> None:
        self._run(self._gw.set_belt(belt, speed_m_s))
        self._speeds[belt] = float(speed_m_s)

    def belt_speed(self, belt: str) -> float:
        return self._speeds[belt]

    def barriers(self) -> dict[str, bool]:
        return self._run(self._gw.barriers())

    def sensed(self) -> np.ndarray | None:
        """What the object sensor sees (None: nothing)."""
        return self._run(self._gw.object_state())

    def observe(self) -> np.ndarray:
        s = self.sensed()
        if s is None:
            raise RuntimeError(f"{self.name}'s object sensor lost the object")
        return s


class GatewayWorld:
    """What a remote module's process knows of its world: the twin's scene (its own
    configuration: belt speed, thresholds, timing) and the unit it is docked at. Nothing
    is simulated; `object_ref` stays None."""

    def __init__(self, scene: SceneConfig) -> None:
        self.scene = scene
        self.object_ref: str | None = None
        self.docked_unit: str | None = None
        self.lock = threading.RLock()

    def undock(self) -> None:
        """The module left its unit."""
        self.docked_unit = None


