"""The transport module on its node: it takes operations from the TMS, runs them through
the flow of Fig. 5.9a (`run_transport_operation` with its skills, `ModuleSkills`, which
reach it through its public side, `ModuleHost`) and reports every step, every moved object
and the result back to the TMS.

The module's process owns the simulation of itself and the unit it is docked at (its
`Environment`): the unit's belts are commanded through the unit's own OPC UA interface
and mirrored into the simulation; the simulated light barriers are written to the unit's
server (`MirroredUnitHAL`), so a virtual unit looks on the wire as a physical one does.

Reports go through a persisted outbox: a report the TMS does not acknowledge (the TMS is
restarting) is sent again until it is, and survives a crash of the module. A module that
restarts in the middle of an operation reports it failed, with the step it was in.
"""

from __future__ import annotations

import asyncio
import contextlib
import functools
import json
import logging
import math
import time
import zlib
from typing import TYPE_CHECKING, Any

import numpy as np

from transfertwin.cps.aas import Capability
from transfertwin.cps.apps import (
    DEFAULT_STATE,
    HOME_POSE,
    FloorRobot,
    docking_model,
    legs_of,
    run_transport_operation,
    take_back,
)
from transfertwin.cps.dispatch import estimate, floor_seconds
from transfertwin.cps.hal import MirroredUnitHAL, environment_for, load_scene
from transfertwin.cps.node import Role, find_partner_ids
from transfertwin.cps.opcua import OpcUaUnitHAL, OperationRefused
from transfertwin.cps.roles._docking import observe_docking, props_docking_estimate

if TYPE_CHECKING:
    from transfertwin.cps.node import AssetNode

__all__ = ["UNCERTAIN_STEPS", "ModuleRole"]

log = logging.getLogger("transfertwin.cps")

#: Steps of an operation during which a failure leaves the object's place unknown (it may
#: lie across the gap).
UNCERTAIN_STEPS = frozenset({"transferring"})


class ModuleRole(Role):
    """A virtual transport module (type E)."""

    def __init__(self, node: AssetNode) -> None:
        super().__init__(node)

        spec = node.floor.module(self.aid)
        self.robot = FloorRobot(node.floor.shop_floor(), home=spec.home or HOME_POSE)
        if self.state.data.get("pose"):  # where it was (a docked pose touches the station)
            self.robot.pose = np.array(self.state.data["pose"], dtype=float)
            self.robot.docked_at = self.state.data.get("station")
        self.env = environment_for(node.cfg, load_scene(),  # virtual or the plant's physics
                                   node.floor.operation.sensor)
        self.op: dict[str, Any] | None = None
        self.face = "front"  # the face the carried object lies on (its load plan's)
        self.attempt = 0  # the hand-over try of the running leg (0: the first)
        self.lost_in_gap = False  # the hand-over policy gave up with the object in the gap
        self.docking = node.cfg.docking
        self.seed = node.cfg.seed
        self._op_id = ""
        self._outbox_kick = asyncio.Event()

    def initial(self) -> dict[str, Any]:
        return {"possesses": [], "pose": None, "docked": "", "current": None, "outbox": []}

    def handlers(self) -> dict[str, Any]:
        return {"SetBeltSpeed": self._set_belt, "SetPossessedObjects": self._set_possessed,
                "AssignOperation": self._assign, "Dock": self._dock_op,
                "ReleaseObject": self._release,
                "Undock": self._undock_op, "Bid": self._bid}  # fmt: skip

    async def start(self) -> None:
        data = self.state.data
        await self.set("PossessedObjects", ",".join(data["possesses"]))
        await self.set("DockedAt", "")
        await self.publish_pose()
        if data["current"] is not None:  # died in the middle of an operation
            cur = data["current"]
            step = cur.get("state", "idle")
            lost = step in UNCERTAIN_STEPS
            self._report(cur["operation"], {
                "event": "result",
                "result": {"status": f"failed while {step}", "failed_step": step,
                           "reason": f"{self.aid} restarted while {step}",
                           "location_unknown": lost, "fault": True},
            })  # fmt: skip
            if lost:
                data["possesses"] = [o for o in data["possesses"] if o != cur["object"]]
            data["current"] = None
            self.state.save()
            log.info("%s: resumed after a crash during %s (%s)", self.aid, cur["operation"], step)
        self.node.spawn(self._flush_outbox())
        self.node.spawn(asyncio.to_thread(_warm_up))  # off the event loop: leases go on

    async def live(self) -> dict[str, Any]:
        x, y, th = (float(v) for v in self.robot.pose)
        return {"state": await self.get("State"), "docked": await self.get("DockedAt") or None,
                "possesses": list(self.state.data["possesses"]),
                "pose": [round(x, 3), round(y, 3), round(th, 4)],
                "operation": (self.op or {}).get("operation")}  # fmt: skip

    # -- belts and possession -------------------------------------------------------------
    def carried(self) -> list[str]:
        """The objects on this module's belts (its own record of them)."""
        return sorted(self.state.data["possesses"])

    def station_of(self, unit: str) -> str:
        """The station of transfer unit `unit` (ValueError: none)."""
        desc = self.node.descriptors.get(unit)
        if desc is None or desc.station is None:
            raise ValueError(f"{unit} stands at no station of the shop floor")
        return desc.station

    async def _set_belt(self, belt: str, speed: float) -> bool:
        if belt not in ("left", "right"):
            raise ValueError(f"unknown belt {belt!r}")
        with self.env.lock:
            if self.env.object_ref is not None:
                self.env.system.tm.set_belt_speed(belt, speed)
        await self.set(f"BeltSpeed{belt.capitalize()}", float(speed))
        return True

    async def _release(self, obj: str) -> bool:
        """An operator took `obj` off this module's belts (`cps locate`): it no longer
        carries it (its own record, Table 3.1). Refused while an operation moves it."""
        if self.op is not None and self.op.get("object") == obj:
            raise ValueError(f"{obj} is being moved by {self.aid} in {self.op['operation']}")
        if obj in self.state.data["possesses"]:
            await self._set_possessed(",".join(o for o in self.state.data["possesses"]
                                               if o != obj))  # fmt: skip
            log.info("%s: an operator took %s off its belts", self.aid, obj)
        return True

    async def _set_possessed(self, objects: str) -> bool:
        self.state.data["possesses"] = sorted(o for o in objects.split(",") if o)
        self.state.save()
        await self.set("PossessedObjects", ",".join(self.state.data["possesses"]))
        return True

    # -- operations -----------------------------------------------------------------------
    async def _bid(self, order: str) -> str:
        """This module's bid for an order (`_dispatch`): expected seconds per candidate
        target from where it stands, by its own planner."""

        doc = json.loads(order)
        units = self.node.floor.units
        targets = [t for t in doc["targets"] if t in units]
        source = doc["source"]
        if not targets or source not in (*units, self.aid):
            raise ValueError(f"no such units in {order}")
        if self.op is not None:
            raise ValueError(f"{self.aid} is busy with {self.op['operation']}")
        stations = self._stations()
        eta = await asyncio.to_thread(estimate, self.robot, stations,
                                      None if source == self.aid else source, targets)
        return json.dumps({"module": self.aid, "eta_s": eta})

    def _stations(self) -> dict[str, str]:
        return {s.unit: s.name for s in self.node.floor.stations}

    async def _assign(self, op_id: str, source: str, target: str, obj: str,
                      plan: str = "{}") -> bool:  # fmt: skip

        if self.op is not None:
            if self.op["operation"] == op_id:
                return True  # the TMS asked again (it restarted): already running
            raise OperationRefused(f"{self.aid} is busy with {self.op['operation']}",
                                   status="BadInvalidState")  # fmt: skip
        if source not in (*self.node.floor.units, self.aid):
            raise OperationRefused(f"no transfer unit {source!r}", argument="source")
        if target not in self.node.floor.units:
            raise OperationRefused(f"no transfer unit {target!r}", argument="target")
        if source == self.aid and obj not in self.state.data["possesses"]:
            # BadNotFound: the TMS tells this from 'busy' (the argument is not sent back)
            raise OperationRefused(f"{obj} is not on {self.aid}", status="BadNotFound",
                                   argument="object")  # fmt: skip
        try:
            doc = json.loads(plan or "{}")
            load, fallback = doc.get("state"), doc.get("fallback")
        except (ValueError, AttributeError):
            raise OperationRefused(f"plan is not a JSON object: {plan!r}",
                                   argument="plan") from None  # fmt: skip
        self.op = {"operation": op_id, "source": source, "target": target, "object": obj,
                   "state": "assigned", "load": load, "fallback": fallback,
                   "start_pose": [float(v) for v in self.robot.pose]}  # fmt: skip
        self.state.data["current"] = dict(self.op)
        self.state.save()
        self.node.spawn(self._run(dict(self.op)))
        return True

    async def _run(self, op: dict[str, Any]) -> None:

        op_id, obj = op["operation"], op["object"]
        await self.set("CurrentTask", f"{op_id}: {obj} {op['source']} -> {op['target']}")

        async def on_state(state: str, leg) -> None:
            await self.set("State", state)
            if self.op is not None and state != "idle":  # 'idle' ends the flow, also on error
                self.op["state"] = state
                self.state.data["current"] = dict(self.op)
                self.state.save()
            self._report(op_id, {"event": "step", "state": state,
                                 "leg": None if leg is None else leg.name,
                                 "unit": None if leg is None else leg.unit})  # fmt: skip

        skills = self._transport(op["source"], op["target"], obj)
        skills.load_state = op.get("load")
        skills.fallback = op.get("fallback")
        skills.camera = self.node.floor.operation.sensor == "camera"
        skills.heights = self.state.data.setdefault("heights", {})  # learnt by the camera
        faces = self.state.data.setdefault("faces", {})  # of the objects on board
        if op["source"] == self.aid:  # on board already: it lies as it was loaded
            self.face = faces.get(obj, "front")
        else:
            self.face = faces[obj] = (op.get("load") or {}).get("face", "front")
        skills.face = self.face
        self._op_id = op_id
        self.lost_in_gap = False
        self.attempt = 0
        try:
            legs = legs_of(op["source"], op["target"])
            if op["source"] == self.aid:  # on board already: the delivery leg only
                legs = legs[1:]
            result = await run_transport_operation(skills, legs, on_state)
        except Exception as exc:  # a peer died mid-step: the operation fails, we go on
            step = (self.op or {}).get("state", "idle")
            log.warning("%s: %s failed while %s: %s", self.aid, op_id, step, exc)
            result = {"status": f"failed while {step}", "failed_step": step,
                      "reason": f"{type(exc).__name__}: {exc}",
                      "location_unknown": step in UNCERTAIN_STEPS, "fault": True}  # fmt: skip
            if step in UNCERTAIN_STEPS:
                self.state.data["possesses"] = [o for o in self.state.data["possesses"]
                                                if o != obj]  # fmt: skip
            await self.undock()
            with self.env.lock:
                self.env.undock()
            await self.set("State", "idle")
        if self.lost_in_gap:  # the hand-over policy gave up with the object in the gap
            result["location_unknown"] = True
            self.state.data["possesses"] = [o for o in self.state.data["possesses"] if o != obj]
        result["docking"] = self.node.cfg.docking
        result["loaded_state"] = skills.load_state  # a retried pick-up may have changed it
        with contextlib.suppress(Exception):  # modelled floor time, for the KPIs

            result["floor_s"] = await asyncio.to_thread(
                floor_seconds, result, self.robot, op.get("start_pose") or self.robot.pose,
                self._stations())  # fmt: skip
        self.op = None
        self.state.data["current"] = None
        self._report(op_id, {"event": "result", "result": result})
        await self.set("CurrentTask", "")

    def _transport(self, source: str, target: str, obj: str):
        """The skills a leg runs with (`TransportSkills`): the simulation's here."""
        from transfertwin.cps.roles._module_skills import ModuleSkills  # the study stack

        return ModuleSkills(self, source, target, obj)

    def _report(self, op_id: str, event: dict[str, Any]) -> None:
        """Queue a report to the TMS (persisted; sent in order until acknowledged)."""
        event = {**event, "module": self.aid, "t": time.time()}
        self.state.data["outbox"].append([op_id, event])
        self.state.save()
        self._outbox_kick.set()

    async def _flush_outbox(self) -> None:
        """Send the queued reports, in order, to the allocator: the asset that realises
        Allocate (`find_partner_ids`; the TMS)."""
        while True:
            outbox = self.state.data["outbox"]
            allocators = await find_partner_ids(self.node, Capability.ALLOCATE) if outbox else []
            while outbox:
                op_id, event = outbox[0]
                try:
                    if not allocators:
                        raise ConnectionError("no online asset realises Allocate")
                    report = json.dumps(event)
                    await asyncio.wait_for(self.node.peers.call(
                        allocators[0], "ReportProgress", op_id, report), 10.0)  # fmt: skip
                except Exception as exc:
                    log.debug("%s: TMS not answering (%s); report kept", self.aid, exc)
                    break
                outbox.pop(0)
                self.state.save()
            self._outbox_kick.clear()
            with contextlib.suppress(TimeoutError):
                await asyncio.wait_for(self._outbox_kick.wait(), 0.5)

    # -- the module's side of its skills (`ModuleHost`) ------------------------------------
    async def publish_pose(self) -> None:
        """Publish and persist the module's floor pose (PoseX, PoseY, PoseTheta)."""
        x, y, theta = (float(v) for v in self.robot.pose)
        for prop, value in (("PoseX", x), ("PoseY", y), ("PoseTheta", theta)):
            await self.set(prop, value)
        self.state.data["pose"] = [x, y, theta]
        self.state.data["station"] = self.robot.docked_at
        self.state.save()

    async def docking_estimate(self, unit: str, error, seed: int):
        """The docking error the transfer uses, and what PropS said of it."""
        observed = functools.partial(observe_docking, self.robot, error, seed)
        return await props_docking_estimate(self, unit, error, observed)  # PropS in the loop

    def docking_error(self, source: str, target: str, obj: str, leg: int):
        """The docking error drawn for this try of leg `leg` (sampled docking)."""
        from transfertwin.study.experiment import experiment_seeds

        key = f"{obj}:{source}:{target}:{self._op_id}:{self.attempt}"
        seed, _ = experiment_seeds(self.node.cfg.seed, key, leg, 0)
        return docking_model().sample(seed)

    def locked(self, fn, *args):
        """`fn(*args)` with the simulation's lock held."""
        with self.env.lock:
            return fn(*args)

    async def dock(self, unit: str) -> bool:
        """Publish the docking at `unit`, on both sides."""
        await self.set("DockedAt", unit)
        try:
            await self.node.peers.write(unit, "DockedTransportModule", self.aid)
        except Exception as exc:
            raise ConnectionError(f"{unit} not answering while docking: {exc}") from None
        return True

    async def undock(self) -> bool:
        """Leave the unit docked at, and clear its docking and barriers."""
        unit = await self.get("DockedAt")
        await self.set("DockedAt", "")
        if unit:
            try:  # the unit's barriers are clear once the module has left
                await self.node.peers.write(unit, "DockedTransportModule", "")
                await self.node.peers.write(unit, "BarrierNearInterrupted", False)
                await self.node.peers.write(unit, "BarrierFarInterrupted", False)
            except Exception as exc:
                log.info("%s: %s not answering while undocking: %s", self.aid, unit, exc)
        return True

    async def _dock_op(self, unit: str) -> bool:
        if unit not in self.node.floor.units:
            raise ValueError(f"no transfer unit {unit!r}")
        return await self.dock(unit)

    async def _undock_op(self) -> bool:
        return await self.undock()

    async def _unit_hal(self, unit: str) -> MirroredUnitHAL:
        """The docked unit's HAL: its OPC UA interface, mirrored into this simulation."""

        session = await self.node.peers.session(unit)
        loop = asyncio.get_running_loop()
        return MirroredUnitHAL(OpcUaUnitHAL(session, loop, timeout_s=10), self.env.system.tu, loop)

    async def transfer(self, unit: str, direction):
        """One OTS between this module and `unit` (its belts over OPC UA, mirrored here)."""
        from transfertwin.study.experiment import scene_controller

        hal = await self._unit_hal(unit)
        system = self.env.system
        camera = self.node.floor.operation.sensor == "camera" and direction.name == "TM_TO_TU"

        def run():  # one thread: the camera's GL context is current in the thread that made it
            vision = self._open_camera() if camera else None
            try:
                ctl = scene_controller(self.env.scene, system.tm, hal, vision or system,
                                       self.env.clock)  # fmt: skip
                return ctl.transfer(direction, self.face, None)
            finally:
                if vision is not None:
                    vision.close()

        try:
            return await asyncio.to_thread(run)
        except Exception:
            await self.node.peers.drop(unit)
            raise

    def _open_camera(self):
        """The delivery's controller sees the object through the module's depth camera
        (`perception.open_sensor`, the study's sensor="perception" path), aimed at where its
        load plan put it."""
        from transfertwin.ots import POSITIONS
        from transfertwin.perception import open_sensor

        load = (self.op or {}).get("load") or DEFAULT_STATE
        xy = POSITIONS[str(load["conveyor"])]
        seed = zlib.crc32(f"{self._op_id}:{self.attempt}".encode())
        return open_sensor(self.env.system, expected_xy=xy,
                           theta_rad=math.radians(float(load["theta_deg"])),
                           seed=seed)  # fmt: skip

    async def take_back(self, unit: str, to_unit: bool = False) -> bool:
        """Reverse both belt pairs (the unit's through its interface) in the simulation
        until the object is back (`cps.apps._hand_over.take_back`)."""

        hal = await self._unit_hal(unit)
        system = self.env.system

        def reverse() -> bool:
            with self.env.lock:
                return take_back(system.tm, hal, system.observe, self.env.clock,
                                 self.env.scene, to_unit)  # fmt: skip

        return await asyncio.to_thread(reverse)

    async def moved(self, obj: str, holder: str) -> None:
        """A transfer put `obj` onto `holder`: this module's possessions and the TMS learn it."""
        own = set(self.state.data["possesses"])
        own.add(obj) if holder == self.aid else own.discard(obj)
        self.state.data["possesses"] = sorted(own)
        self.state.save()
        await self.set("PossessedObjects", ",".join(self.state.data["possesses"]))
        self._report(self._op_id, {"event": "moved", "object": obj, "holder": holder})


def _warm_up() -> None:
    """Fit the docking-error generator once (about 0.6 s) before the first operation."""

    docking_model()
