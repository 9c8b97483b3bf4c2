"""The virtual environment: the logical asset that simulates the world of the virtual models
and its time (Sec. 3.2).

It owns the MuJoCo system of the transport module and the unit it is docked at, and a clock
that steps the physics and, when `time_scale` > 0, keeps pace with the wall clock (scaled
real time: 1.0 = real time, 2.0 = twice as fast; 0 = as fast as possible). After every step
it lets the docked units synchronise their own state (their light barriers), exactly as a
physical unit's firmware would.
"""

from __future__ import annotations

import math
import threading
import time
from collections.abc import Callable

from transfertwin.sim import DockingError, SceneConfig, VirtualTransferSystem
from transfertwin.study.experiment import system_for

__all__ = ["Environment", "ScaledClock"]


class ScaledClock:
    """`transfertwin.control.Clock` over the simulation, paced against the wall clock."""

    def __init__(self, env: Environment) -> None:
        self._env = env
        self._wall0 = time.monotonic()
        self._sim0 = 0.0

    def now(self) -> float:
        """Simulated seconds since `start`."""
        return self._env.system.clock.now()

    def start(self) -> None:
        """Zero the clock."""
        self._env.system.clock.start()
        self._wall0, self._sim0 = time.monotonic(), self._env.system.time_s

    def wait(self, dt_s: float) -> None:
        """Step the physics by `dt_s`, then sync the docked unit and keep pace."""
        self._env.system.clock.wait(dt_s)
        scale = self._env.time_scale
        if scale > 0:
            ahead = (self._env.system.time_s - self._sim0) / scale - (
                time.monotonic() - self._wall0
            )
            if ahead > 0:
                time.sleep(ahead)


class Environment:
    """The simulated world of one transport module and the unit it is docked at.

    Args:
        scene: Virtual system configuration.
        time_scale: Simulated seconds per wall second (0: as fast as possible).
        systems: The system of an object (cached by the callee); default: the twin's virtual
            system of the scene. A plant floor's module passes the plant's
            (`transfertwin.plant.PlantPhysics.system`: MuJoCo, or PyBullet on a 'bullet'
            plant), which steps through the same surface.
    """

    def __init__(
        self, scene: SceneConfig, time_scale: float = 0.0,
        systems: Callable[[str], VirtualTransferSystem] | None = None,
    ) -> None:  # fmt: skip
        self.scene = scene
        self.time_scale = time_scale
        self._systems = systems or (lambda object_ref: system_for(object_ref, "m", scene))
        self.object_ref: str | None = None
        self.docked_unit: str | None = None
        self._system: VirtualTransferSystem | None = None
        self._listeners: list[Callable[[VirtualTransferSystem, str | None], None]] = []
        self.lock = threading.RLock()
        self.clock = ScaledClock(self)

    @property
    def system(self) -> VirtualTransferSystem:
        """The simulated TM + TU + object."""
        if self._system is None:
            raise RuntimeError("no object loaded into the virtual environment")
        return self._system

    def on_step(self, listener: Callable[[VirtualTransferSystem, str | None], None]) -> None:
        """Call `listener(system, docked_unit)` after every clock step."""
        self._listeners.append(listener)

    def after_step(self) -> None:
        """Let listeners synchronise (called by the system's clock after every wait)."""
        for listener in self._listeners:
            listener(self.system, self.docked_unit)

    def use(self, object_ref: str) -> VirtualTransferSystem:
        """Make the (cached) system of `object_ref` the environment's system."""
        system = self._systems(object_ref)
        if self.after_step not in system.step_listeners:
            system.step_listeners.append(self.after_step)
        self._system = system
        self.object_ref = object_ref
        return system

    def load_object_at_unit(
        self, object_ref: str, unit: str, error: DockingError, face: str = "front",
        theta_deg: float = 0.0, y_offset_m: float = 0.0,
    ) -> None:  # fmt: skip
        """Dock the TM at `unit` with `error` and put the object on that unit's belts (on
        `face`, yaw `theta_deg`, `y_offset_m` off the unit's centre line)."""
        self.use(object_ref)
        self._system.reset(error)
        self._system.place_on_unit(face, math.radians(theta_deg), y_offset_m)
        self.docked_unit = unit
        self._system.clock.wait(self.scene.placement.settle_time_s)

    def dock(self, unit: str, error: DockingError) -> None:
        """Dock at another unit; the object stays where it is (on the TM)."""
        self.system.dock(error)
        self.docked_unit = unit

    def undock(self) -> None:
        """Leave the docked unit."""
        self.docked_unit = None
