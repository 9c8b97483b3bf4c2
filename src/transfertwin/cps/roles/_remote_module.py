"""A transport module on real hardware (``[hal] kind = "remote"``): its process runs the
operation flow of Fig. 5.9a against the module's HAL gateway instead of a simulation
(docs/architecture.md, "Deployment": the gateway's node set).

- **Drive.** Navigating and docking are the module's own (its navigation and laser docking
  run on the machine): the asset writes ``Command`` = ``"<seq> navigate <station>"``,
  ``"<seq> dock <station>"`` or ``"<seq> undock"`` and waits until ``CommandState`` says
  ``"<seq> done"`` or ``"<seq> failed: <why>"`` (``"<seq> busy"`` meanwhile).
- **Pose.** ``PoseX``, ``PoseY``, ``PoseTheta`` (m, rad, floor frame: the module's
  localisation) are read every ``poll_s`` (at most 5 Hz) and published. The docking error
  is the docked pose relative to the station's goal pose.
- **Object sensing.** ``ObjectState`` (Double[8]: a, x, y, z, s_x, s_y, s_z, θ in F_T of
  the docked pair; NaN: nothing seen) is the module's vision system. The OTS is formed from
  it and the OTS controller observes it.
- **Belts and barriers.** The module's own belts and barriers are the gateway's
  (`ModuleGateway`); the docked unit's are the unit's (its OPC UA interface: the unit's
  process writes them to its own gateway).
- **Hand-over retries.** The virtual module's policy (`cps.apps._hand_over`): a failed transfer
  is taken back with both belt pairs reversed until the object sensor sees it back, the
  module undocks and docks anew by command and tries again.
- **PropS.** At every docking the gateway's pose is reported to PropS and the leg's
  docking error is its fused estimate (where the floor has PropS).

The transfer loop runs on the wall clock (`WallClock`), in a worker thread, each HAL call a
request on the event loop that owns the gateway session.
"""

from __future__ import annotations

import asyncio
import contextlib
import logging
import math
import time

import numpy as np

from transfertwin._errors import InputError
from transfertwin.cps.apps import HandOverRetries, StepResult, form_ots, take_back, transfer_step
from transfertwin.cps.hal import (
    GatewayError,
    ModuleGateway,
    ThreadHAL,
    WallClock,
    gateway_refusal,
    poll_gateway,
)
from transfertwin.cps.opcua import OpcUaUnitHAL
from transfertwin.cps.roles._docking import props_docking_estimate
from transfertwin.cps.roles._module import ModuleRole
from transfertwin.navigation import relative
from transfertwin.ots import BeltThresholds, TransferDirection
from transfertwin.perception import AABB
from transfertwin.sim import DockingError

__all__ = ["RemoteModuleRole"]

log = logging.getLogger("transfertwin.cps")


class GatewaySteps:
    """The steps of a leg (`TransportSkills`) on the module's hardware, one try each."""

    load_state: dict | None = None
    camera = False
    face = "front"

    def __init__(self, host: RemoteModuleRole, source: str, target: str, obj: str):
        self.host = host
        self.obj, self.source, self.target = obj, source, target

    def _station(self, leg) -> str:
        return self.host.station_of(leg.unit)

    async def navigate(self, leg) -> StepResult:
        station = self._station(leg)
        t0 = time.monotonic()
        ok, why = await self.host.gateway.command("navigate", station)
        await self.host.refresh_pose()
        return StepResult(ok, why, {"station": station,
                                    "drive_s": round(time.monotonic() - t0, 2)})

    async def dock(self, leg) -> StepResult:
        role, station = self.host, self._station(leg)
        role.at_station = station  # a failed dock is undocked from too
        ok, why = await role.gateway.command("dock", station)
        pose = await role.refresh_pose()
        goal = role.robot.floor.station(station).goal_pose()
        xi = tuple(float(v) for v in relative(goal, pose))
        info = {"station": station, **_error_info(xi),
                "source": "the module's localisation at the gateway"}  # fmt: skip
        if not ok:
            return StepResult(False, f"docking at {leg.unit}: {why}", info)
        try:
            err = DockingError(*xi)
        except InputError as exc:  # an error the pair cannot work with
            await role.undock()
            return StepResult(False, f"docking at {leg.unit}: {exc}", info)
        used, props = await role.fused_error(leg.unit, err, pose)
        if props is not None:  # PropS in the loop: its fused estimate is the record's
            info["props"] = props
            if props["used"] == "fused":
                info |= {**_error_info((used.x_m, used.y_m, used.theta_rad)),
                         "source": "PropS's fused estimate"}  # fmt: skip
        role.robot.docked_at = station
        role.env.docked_unit = leg.unit
        await role.dock(leg.unit)
        return StepResult(True, info=info)

    async def form_ots(self, leg) -> StepResult:
        role = self.host
        s = await role.gateway.object_state()
        boxes = [] if s is None else [AABB(tuple(float(v) for v in s[1:4]),
                                           tuple(float(v) for v in s[4:7]))]  # fmt: skip
        pickup = leg.direction is TransferDirection.TU_TO_TM
        check = form_ots(boxes, leg.direction, BeltThresholds(t_max=role.env.scene.t_max_s),
                         obj=self.obj, tm=role.aid, unit=leg.unit,
                         receiver_holds=role.carried() if pickup else [],
                         face=self.face)  # fmt: skip
        info = {"source": "object sensor at the gateway",
                "boxes": [b.as_dict() for b in boxes]}  # fmt: skip
        log.info("%s: sensed %s and itself: %d object(s)%s", role.aid, leg.unit,
                 len(boxes), "" if check.ok else f"; no OTS: {check.reason}")  # fmt: skip
        return StepResult(check.ok, check.reason, info)

    async def transfer(self, leg) -> StepResult:
        rec = await self.host.transfer(leg.unit, leg.direction)
        log.info("%s: %s %s at %s: y = %d", self.host.aid, leg.name, self.obj, leg.unit,
                 rec.y)  # fmt: skip
        return transfer_step(rec)

    async def resolve(self, leg, success: bool) -> None:
        role = self.host
        if success:
            await role.moved(self.obj, role.aid if leg.name == "pick-up" else leg.unit)
        await role.undock()

class GatewaySkills(HandOverRetries, GatewaySteps):
    """The steps of a leg on the module's hardware with the hand-over policy: a failed
    transfer is taken back with the belts at the gateway and tried again after a dock
    commanded anew."""


def _error_info(xi) -> dict[str, float]:
    """A docking error (x m, y m, θ rad) as a leg's record holds it."""
    return {"x_mm": round(xi[0] * 1e3, 3), "y_mm": round(xi[1] * 1e3, 3),
            "theta_deg": round(math.degrees(xi[2]), 4)}  # fmt: skip


class RemoteModuleRole(ModuleRole):
    """A transport module on real hardware behind its HAL gateway (see the module
    docstring). Everything else (operations, reports, possession, bids) is `ModuleRole`'s."""

    def __init__(self, node) -> None:
        super().__init__(node)  # its environment is a `GatewayWorld` (`environment_for`)
        self.gateway = ModuleGateway(node.cfg)
        self.at_station: str | None = None  # a dock was commanded there (done or not)

    def _transport(self, source: str, target: str, obj: str):
        return GatewaySkills(self, source, target, obj)

    async def start(self) -> None:
        with contextlib.suppress(GatewayError):  # where the machine stands, if it answers
            await self.refresh_pose()
        await super().start()
        self.node.spawn(self._poll_pose())

    async def stop(self) -> None:
        await self.gateway.close()

    async def refresh_pose(self) -> np.ndarray:
        """The module's pose at the gateway, published when it changed."""
        pose = await self.gateway.pose()
        if not np.array_equal(pose, self.robot.pose):
            self.robot.pose = pose
            await self.publish_pose()
        return pose

    async def fused_error(self, unit: str, error, pose):
        """PropS in the loop: the module's localisation fix at the gateway (`pose`, with
        the σ of the module's navigation model) reported to PropS, and the docking error
        taken from its fused estimate ((error used, the record's ``props``), as
        `ModuleRole.docking_estimate` does with a simulated fix). No unit camera is seen
        from here (a unit on real hardware would report its own)."""
        noise = self.robot.cfg.noise
        own = (*(float(v) for v in pose), noise.loc_xy_sd_m, noise.loc_theta_sd_rad)
        return await props_docking_estimate(self, unit, error, lambda: (own, None),
                                            measured="gateway")  # fmt: skip

    async def _poll_pose(self) -> None:
        """Publish the module's pose as the gateway reports it (a gateway away: said once,
        kept trying)."""
        await poll_gateway(self.aid, self.refresh_pose, max(self.node.cfg.hal.poll_s, 0.2))

    async def _set_belt(self, belt: str, speed: float) -> bool:
        try:  # the drive first: then publish
            await self.gateway.set_belt(belt, float(speed))
        except GatewayError as exc:
            raise gateway_refusal(exc) from None
        await self.set(f"BeltSpeed{belt.capitalize()}", float(speed))
        return True

    async def _dock_op(self, unit: str) -> bool:
        if unit not in self.node.floor.units:
            raise ValueError(f"no transfer unit {unit!r}")
        station = self.station_of(unit)
        for verb in ("navigate", "dock"):
            self.at_station = station if verb == "dock" else self.at_station
            ok, why = await self.gateway.command(verb, station)
            if not ok:
                raise RuntimeError(why)
        await self.refresh_pose()
        return await self.dock(unit)

    async def undock(self) -> bool:
        """Leave the docked unit, or the station a dock was tried at (the drive first); the
        unit's barriers are its hardware's."""
        unit = await self.get("DockedAt")
        if unit or self.at_station:
            try:
                ok, why = await self.gateway.command("undock")
            except GatewayError as exc:
                ok, why = False, str(exc)
            if not ok:
                log.warning("%s: %s", self.aid, why)
            self.at_station = None
        await self.set("DockedAt", "")
        self.robot.docked_at = None
        self.env.undock()
        if unit:
            try:
                await self.node.peers.write(unit, "DockedTransportModule", "")
            except Exception as exc:
                log.info("%s: %s not answering while undocking: %s", self.aid, unit, exc)
        return True

    async def _pair(self, unit: str, work):
        """Run `work(tm, tu)` in a worker thread with the docked pair's HALs: the module's
        at the gateway (`ThreadHAL`) and `unit`'s OPC UA interface."""

        loop = asyncio.get_running_loop()
        session = await self.node.peers.session(unit)
        tu = OpcUaUnitHAL(session, loop, timeout_s=10)
        tm = ThreadHAL(self.aid, self.gateway, loop)
        try:
            return await asyncio.to_thread(work, tm, tu)
        except Exception:
            await self.node.peers.drop(unit)
            raise

    async def transfer(self, unit: str, direction):
        """One transfer between the module and the docked `unit` on the hardware: the OTS
        controller with the module's gateway, the unit's OPC UA interface and the wall
        clock."""
        from transfertwin.study.experiment import scene_controller

        face = self.face

        def work(tm, tu):
            ctl = scene_controller(self.env.scene, tm, tu, tm, WallClock())
            return ctl.transfer(direction, face, None)

        return await self._pair(unit, work)

    async def take_back(self, unit: str, to_unit: bool = False) -> bool:
        """Reverse the module's belts at the gateway and `unit`'s through its interface
        until the object sensor sees the object back (`cps.apps._hand_over.take_back`, on the
        wall clock)."""

        def work(tm, tu):
            return take_back(tm, tu, tm.sensed, WallClock(), self.env.scene, to_unit)

        return await self._pair(unit, work)
