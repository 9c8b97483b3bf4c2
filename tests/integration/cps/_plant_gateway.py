"""A HAL gateway as the machines' PLC would serve it, for the remote-HAL tests: a real
asyncua server on loopback, in a thread of its own, whose nodes a MuJoCo transfer system
drives in real time (the node set of docs/architecture.md, "Deployment").

The "hardware" is the virtual scene's physics (`cps.apps.Environment`): the belts run at
the speeds written to the gateway's belt nodes; the light barriers, the module's object
sensor (the system's observed state in F_T, NaN while it is not docked at the pair that
holds the object) and the module's pose are written back every tick. The module's drive
answers the commands ``navigate`` (to the station's coarse pose), ``dock`` (at the goal
pose composed with a docking error drawn from `seed`; the pair's physics docks with that
error) and ``undock``. Which unit holds the object afterwards is read off the physics.
"""

from __future__ import annotations

import asyncio
import contextlib
import math
import threading
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from asyncua import Server, ua

TICK_S = 0.01
DRIVE_S = 0.15  # how long the drive takes for a command (wall)


@dataclass
class PlantLog:
    """What the plant saw (for the test's checks)."""

    errors: list[tuple[str, tuple[float, float, float]]] = field(default_factory=list)
    belts: dict[str, float] = field(default_factory=dict)  # node -> largest |speed|
    barriers: set[str] = field(default_factory=set)  # barrier nodes that were interrupted
    commands: list[str] = field(default_factory=list)
    signs: dict[str, set[int]] = field(default_factory=dict)  # node -> directions it ran
    jammed_s: float = 0.0  # how long the module's belts stood jammed (wall)
    #: The module's drive as the gateway saw it, on every change: (wall s since start,
    #: belt, commanded speed, speed run) — what a failed hand-over test shows.
    drive: list[tuple[float, str, float, float]] = field(default_factory=list)


class PlantGateway:
    """The gateway and the plant behind it (start with `start`, end with `stop`).

    Args:
        port: Loopback port.
        module: The transport module's id; `units`: unit id -> its station.
        obj: The object; `at`: the unit it lies on.
        seed: Seed of the docking errors.
        secure: (gateway cert, key, trust folder) for Basic256Sha256 SignAndEncrypt only;
            None: NoSecurity.
        jam: The module's belt drive trips once: its belts stand still from the first time
            either is commanded to run until neither is commanded to run that way any more
            (both stopped or reversed; then it is reset and runs as commanded). Both belts
            count: the module writes them one at a time, and a tick can read the first
            written and the second not yet; a reversal counts as well as a stop, because
            the tick samples the nodes and may miss a stop between two runs.
    """

    def __init__(self, port: int, module: str, units: dict[str, str], obj: str, at: str,
                 seed: int, secure: tuple[Path, Path, Path] | None = None,
                 jam: bool = False) -> None:  # fmt: skip
        from transfertwin.cps import default_floor_spec

        self.url = f"opc.tcp://127.0.0.1:{port}/gateway"
        self.module, self.units, self.obj = module, units, obj
        self.holder = at
        self.docked: str | None = None
        self.floor = default_floor_spec().shop_floor()
        self._env = None
        self.rng = np.random.default_rng(seed)
        self.pose = np.array([6.0, 5.2, 0.0])
        self.secure = secure
        self.log = PlantLog()
        self._jam = "armed" if jam else "off"  # armed -> jammed -> reset
        self._jam_t0 = 0.0
        self._commanded: dict[str, float] = {}  # the module's belt -> its commanded speed
        self._jam_sign = 1.0  # the direction the drive tripped in
        self._t_start = time.monotonic()
        self._loop: asyncio.AbstractEventLoop | None = None
        self._thread: threading.Thread | None = None
        self._ready = threading.Event()
        self._stop: asyncio.Event | None = None
        self._failed: BaseException | None = None

    @property
    def env(self):
        """The machines' physics (made on first use: a gateway that only serves needs none)."""
        if self._env is None:
            from transfertwin.cps.apps import Environment
            from transfertwin.cps.hal import load_scene

            self._env = Environment(load_scene(), time_scale=0.0)
        return self._env

    # -- life cycle ------------------------------------------------------------------------
    def start(self) -> PlantGateway:
        self._thread = threading.Thread(target=self._main, daemon=True)
        self._thread.start()
        assert self._ready.wait(30), "the gateway did not start"
        if self._failed is not None:
            raise self._failed
        return self

    def stop(self) -> None:
        """Stop serving (the machine's controller is switched off); again: nothing."""
        if self._thread is not None and self._thread.is_alive():
            self._loop.call_soon_threadsafe(self._stop.set)
        if self._thread is not None:
            self._thread.join(20)
        if self._failed is not None:
            raise self._failed

    def value(self, key: str):
        """The gateway's node `key` ('<asset>.<name>') now (from any thread)."""
        return asyncio.run_coroutine_threadsafe(self._read(key), self._loop).result(10)

    def set(self, key: str, value) -> None:
        """Write the gateway's node `key` as the machine would (from any thread)."""
        asyncio.run_coroutine_threadsafe(self._write(key, value), self._loop).result(10)

    def _main(self) -> None:
        asyncio.run(self._serve())

    async def _serve(self) -> None:
        self._loop = asyncio.get_running_loop()
        self._stop = asyncio.Event()
        try:
            server = await self._server()
        except BaseException as exc:
            self._failed = exc
            self._ready.set()
            return
        self._ready.set()
        try:
            await self._run()
        except BaseException as exc:  # a failure of the plant fails the test
            self._failed = exc
        finally:
            iserver = server.iserver
            if iserver.time_task is not None:  # its 1 s sleep would hold the stop
                iserver.time_task.cancel()
                with contextlib.suppress(asyncio.CancelledError):
                    await iserver.time_task
                iserver.time_task = None
            await server.stop()

    async def _server(self) -> Server:
        from transfertwin.cps.opcua._aspace import share_standard_address_space

        server = Server()
        share_standard_address_space(server)  # not built anew: seconds on a busy machine
        await server.init()
        server.set_endpoint(self.url)
        if self.secure is None:
            server.set_security_policy([ua.SecurityPolicyType.NoSecurity])
        else:
            from transfertwin.cps.opcua import TrustList

            cert, key, trust = self.secure
            await server.load_certificate(str(cert))
            await server.load_private_key(str(key))
            server.set_security_policy([ua.SecurityPolicyType.Basic256Sha256_SignAndEncrypt])
            server.set_certificate_validator(TrustList(trust))
        ns = await server.register_namespace("urn:example:plc")
        assert ns == 2  # the asset files' default NodeIds name namespace 2
        plc = await server.nodes.objects.add_object(ns, "PLC")
        self.nodes: dict[str, object] = {}
        names = [(u, n, v) for u in self.units for n, v in
                 (("BeltSpeedLeft", 0.0), ("BeltSpeedRight", 0.0), ("BarrierNear", False),
                  ("BarrierFar", False))]  # fmt: skip
        m = self.module
        names += [(m, "BeltSpeedLeft", 0.0), (m, "BeltSpeedRight", 0.0), (m, "BarrierNear", False),
                  (m, "BarrierFar", False), (m, "PoseX", float(self.pose[0])),
                  (m, "PoseY", float(self.pose[1])), (m, "PoseTheta", float(self.pose[2])),
                  (m, "Command", ""), (m, "CommandState", ""),
                  (m, "ObjectState", [math.nan] * 8)]  # fmt: skip
        for asset, name, value in names:
            vtype = ua.VariantType.Double if isinstance(value, float | list) else None
            node = await plc.add_variable(ua.NodeId(f"{asset}.{name}", ns), name,
                                          ua.Variant(value, vtype) if vtype else value)
            await node.set_writable()
            self.nodes[f"{asset}.{name}"] = node
        await server.start()
        return server

    # -- the plant -------------------------------------------------------------------------
    async def _read(self, key: str):
        return await self.nodes[key].read_value()

    async def _write(self, key: str, value) -> None:
        vtype = ua.VariantType.Double if isinstance(value, float | list) else None
        await self.nodes[key].write_value(ua.Variant(value, vtype) if vtype else value)

    def _drive(self, asset: str, belt: str, speed: float) -> float:
        """The speed `asset`'s `belt` runs at when commanded `speed` (the jam, if armed)."""
        if asset != self.module:
            return speed
        changed = self._commanded.get(belt) != speed
        self._commanded[belt] = speed
        if self._jam == "armed" and speed:
            self._jam, self._jam_t0 = "jammed", time.monotonic()
            self._jam_sign = math.copysign(1.0, speed)
        # reset once neither belt is commanded to run the jammed way any more (stopped or
        # reversed): the tick samples the nodes, and a stop between two runs may be missed
        if self._jam == "jammed" and not any(
            v * self._jam_sign > 0 for v in self._commanded.values()
        ):
            self._jam = "off"
            self.log.jammed_s = time.monotonic() - self._jam_t0
        run = 0.0 if self._jam == "jammed" else speed
        if changed:
            self.log.drive.append((round(time.monotonic() - self._t_start, 3), belt, speed, run))
        return run

    def _in_pair(self) -> bool:
        return self.docked is not None and self.holder in (self.module, self.docked)

    def _settle_holder(self) -> None:
        """Who holds the object, read off the physics (the docked pair only)."""
        if self._in_pair():
            x = float(self.env.system.observe()[1])
            self.holder = self.docked if x > self.env.scene.gap_m / 2 else self.module

    async def _command(self, text: str) -> None:
        from transfertwin.navigation import DockingConfig, compose
        from transfertwin.sim import DockingError

        seq, verb, *rest = text.split()
        self.log.commands.append(f"{verb} {' '.join(rest)}".strip())
        m = self.module
        await self._write(f"{m}.CommandState", f"{seq} busy")
        await asyncio.sleep(DRIVE_S)
        station = rest[0] if rest else None
        unit = next((u for u, s in self.units.items() if s == station), None)
        if verb == "navigate":
            self.pose = self.floor.station(station).coarse_pose(DockingConfig().coarse_distance_m)
        elif verb == "dock":
            if unit is None:
                await self._write(f"{m}.CommandState", f"{seq} failed: no unit at {station}")
                return
            xi = (float(self.rng.normal(0, 1e-3)), float(self.rng.normal(0, 1e-3)),
                  float(self.rng.normal(0, math.radians(0.2))))  # fmt: skip
            err = DockingError(*xi)
            self.log.errors.append((station, xi))
            self.pose = compose(self.floor.station(station).goal_pose(), np.array(xi))
            if self.holder == unit:
                self.env.load_object_at_unit(self.obj, unit, err)
            elif self.holder == m:
                self.env.dock(unit, err)
            self.docked = unit
        elif verb == "undock":
            self._settle_holder()
            if self.docked is not None:
                await self._write(f"{self.docked}.BarrierNear", False)
                await self._write(f"{self.docked}.BarrierFar", False)
            self.docked = None
            self.env.undock()
        else:
            await self._write(f"{m}.CommandState", f"{seq} failed: unknown command {verb!r}")
            return
        for key, v in zip(("PoseX", "PoseY", "PoseTheta"), self.pose, strict=True):
            await self._write(f"{m}.{key}", float(v))
        await self._write(f"{m}.CommandState", f"{seq} done")

    async def _run(self) -> None:
        m, last = self.module, ""
        sim_t, wall0 = 0.0, time.monotonic()
        while not self._stop.is_set():
            command = str(await self._read(f"{m}.Command") or "")
            if command and command != last:
                last = command
                await self._command(command)
                sim_t, wall0 = 0.0, time.monotonic()
            if self._in_pair():
                system = self.env.system
                for who, hal in ((m, system.tm), (self.docked, system.tu)):
                    for belt in ("left", "right"):
                        key = f"{who}.BeltSpeed{belt.capitalize()}"
                        speed = float(await self._read(key))
                        self.log.belts[key] = max(self.log.belts.get(key, 0.0), abs(speed))
                        if speed:
                            self.log.signs.setdefault(key, set()).add(1 if speed > 0 else -1)
                        hal.set_belt_speed(belt, self._drive(who, belt, speed))
                target = time.monotonic() - wall0  # real time: the physics keeps pace
                steps = int((target - sim_t) / self.env.scene.physics.timestep_s)
                if steps > 0:
                    system.clock.wait(steps * self.env.scene.physics.timestep_s)
                    sim_t += steps * self.env.scene.physics.timestep_s
                for who, hal in ((m, system.tm), (self.docked, system.tu)):
                    for side, on in hal.barriers().items():
                        key = f"{who}.Barrier{side.capitalize()}"
                        if on:
                            self.log.barriers.add(key)
                        await self._write(key, bool(on))
                seen = [float(v) for v in system.observe()]
            else:
                sim_t, wall0 = 0.0, time.monotonic()
                seen = [math.nan] * 8
            await self._write(f"{m}.ObjectState", seen)
            await asyncio.sleep(TICK_S)
