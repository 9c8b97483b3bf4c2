"""The transport module in its own process: it takes operations from the TMS, runs them
through the flow of Fig. 5.9a (`run_transport_operation`, the same skills as the
single-process CPS, `VirtualTransport`) and reports every step, every moved object and
the result back to the TMS.

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
from types import SimpleNamespace
from typing import TYPE_CHECKING, Any

import numpy as np

from transfertwin.cps.hal import MirroredUnitHAL, load_scene
from transfertwin.cps.node import Role

if TYPE_CHECKING:
    from transfertwin.cps.node import AssetNode

__all__ = ["CAMERA_SIGMA_THETA_RAD", "CAMERA_SIGMA_XY_M", "UNCERTAIN_STEPS", "ModuleRole"]

log = logging.getLogger("transfertwin.cps")

#: Steps of an operation during which a failure leaves the object's place unknown (it may
#: lie across the gap).
UNCERTAIN_STEPS = frozenset({"transferring"})


class ModuleRole(Role):
    """A virtual transport module (type E)."""

    def __init__(self, node: AssetNode) -> None:
        super().__init__(node)
        from transfertwin.cps.apps import HOME_POSE, FloorRobot
        from transfertwin.cps.hal import environment_for

        spec = node.floor.module(self.aid)
        self.robot = FloorRobot(node.floor.shop_floor(), home=spec.home or HOME_POSE)
        if self.state.data.get("pose"):  # where it was (a docked pose touches the station)
            self.robot.pose = np.array(self.state.data["pose"], dtype=float)
            self.robot.docked_at = self.state.data.get("station")
        self.env = environment_for(node.cfg, load_scene())  # virtual or the plant's physics
        self.op: dict[str, Any] | None = None
        self._face = "front"  # the face the carried object lies on (its load plan's)
        self._outbox_kick = asyncio.Event()
        # what `VirtualTransport` reads of the runtime it serves
        self.floor_robots = {self.aid: self.robot}
        self.config = SimpleNamespace(docking=node.cfg.docking, seed=node.cfg.seed,
                                      scene=self.env.scene)  # fmt: skip
        self.assets = {d.asset_id: SimpleNamespace(desc=d) for d in node.descriptors.values()}
        self.ledger = SimpleNamespace(objects_at=self._objects_at)

    def initial(self) -> dict[str, Any]:
        return {"possesses": [], "pose": None, "docked": "", "current": None, "outbox": []}

    def handlers(self) -> dict[str, Any]:
        return {"SetBeltSpeed": self._set_belt, "SetPossessedObjects": self._set_possessed,
                "AssignOperation": self._assign, "Dock": self._dock_op,
                "Undock": self._undock_op, "Bid": self._bid}  # fmt: skip

    async def start(self) -> None:
        data = self.state.data
        await self.set("PossessedObjects", ",".join(data["possesses"]))
        await self.set("DockedAt", "")
        await self._publish_pose(self.aid)
        if data["current"] is not None:  # died in the middle of an operation
            cur = data["current"]
            step = cur.get("state", "idle")
            lost = step in UNCERTAIN_STEPS
            self._report(cur["operation"], {
                "event": "result",
                "result": {"status": f"failed while {step}", "failed_step": step,
                           "reason": f"{self.aid} restarted while {step}",
                           "location_unknown": lost},
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
    def _objects_at(self, holder: str) -> list[str]:
        return sorted(self.state.data["possesses"]) if holder == self.aid else []

    async def _set_belt(self, belt: str, speed: float) -> bool:
        if belt not in ("left", "right"):
            raise ValueError(f"unknown belt {belt!r}")
        with self.env.lock:
            if self.env.object_ref is not None:
                self.env.system.tm.set_belt_speed(belt, speed)
        await self.set(f"BeltSpeed{belt.capitalize()}", float(speed))
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
        from transfertwin.cps.dispatch import estimate

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
        from transfertwin.cps.opcua import OperationRefused

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
        from transfertwin.cps.apps import legs_of, run_transport_operation

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
            self._face = faces.get(obj, "front")
        else:
            self._face = faces[obj] = (op.get("load") or {}).get("face", "front")
        skills.face = self._face
        self._op_id = op_id
        self._lost_in_gap = False
        self._attempt = 0
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
                      "location_unknown": step in UNCERTAIN_STEPS}  # fmt: skip
            if step in UNCERTAIN_STEPS:
                self.state.data["possesses"] = [o for o in self.state.data["possesses"]
                                                if o != obj]  # fmt: skip
            await self._undock(self.aid)
            with self.env.lock:
                self.env.undock()
            await self.set("State", "idle")
        if self._lost_in_gap:  # the hand-over policy gave up with the object in the gap
            result["location_unknown"] = True
            self.state.data["possesses"] = [o for o in self.state.data["possesses"] if o != obj]
        result["docking"] = self.node.cfg.docking
        result["loaded_state"] = skills.load_state  # a retried pick-up may have changed it
        with contextlib.suppress(Exception):  # modelled floor time, for the KPIs
            from transfertwin.cps.dispatch import floor_seconds

            result["floor_s"] = await asyncio.to_thread(
                floor_seconds, result, self.robot, op.get("start_pose") or self.robot.pose,
                self._stations())  # fmt: skip
        self.op = None
        self.state.data["current"] = None
        self._report(op_id, {"event": "result", "result": result})
        await self.set("CurrentTask", "")

    def _transport(self, source: str, target: str, obj: str):
        """The skills a leg runs with (`TransportSkills`): the simulation's here."""
        return _ModuleTransport(self, self.aid, source, target, obj)

    def _report(self, op_id: str, event: dict[str, Any]) -> None:
        """Queue a report to the TMS (persisted; sent in order until acknowledged)."""
        event = {**event, "module": self.aid, "t": time.time()}
        self.state.data["outbox"].append([op_id, event])
        self.state.save()
        self._outbox_kick.set()

    async def _flush_outbox(self) -> None:
        while True:
            outbox = self.state.data["outbox"]
            while outbox:
                op_id, event = outbox[0]
                try:
                    await asyncio.wait_for(self.node.peers.call(
                        "TMS", "ReportProgress", op_id, json.dumps(event)), 10.0)  # fmt: skip
                except Exception as exc:
                    log.debug("%s: TMS not answering (%s); report kept", self.aid, exc)
                    break
                outbox.pop(0)
                self.state.save()
            self._outbox_kick.clear()
            with contextlib.suppress(TimeoutError):
                await asyncio.wait_for(self._outbox_kick.wait(), 0.5)

    # -- what `VirtualTransport` calls --------------------------------------------------------
    async def _publish_pose(self, tm: str) -> None:
        x, y, theta = (float(v) for v in self.robot.pose)
        for prop, value in (("PoseX", x), ("PoseY", y), ("PoseTheta", theta)):
            await self.set(prop, value)
        self.state.data["pose"] = [x, y, theta]
        self.state.data["station"] = self.robot.docked_at
        self.state.save()

    async def _docking_estimate(self, tm: str, unit: str, error, seed: int):
        observed = functools.partial(_observe_docking, self.robot, error, seed)
        return await _props_docking_estimate(self, tm, unit, error, observed)  # PropS in the loop

    def _error(self, source: str, target: str, obj: str, leg: int):
        from transfertwin.cps.apps import docking_model
        from transfertwin.study.experiment import experiment_seeds

        key = f"{obj}:{source}:{target}:{self._op_id}:{self._attempt}"
        seed, _ = experiment_seeds(self.node.cfg.seed, key, leg, 0)
        return docking_model().sample(seed)

    def _locked(self, fn, *args):
        with self.env.lock:
            return fn(*args)

    async def _dock(self, tm: str, unit: str) -> bool:
        await self.set("DockedAt", unit)
        try:
            await self.node.peers.write(unit, "DockedTransportModule", self.aid)
        except Exception as exc:
            raise ConnectionError(f"{unit} not answering while docking: {exc}") from None
        return True

    async def _undock(self, tm: str) -> bool:
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
        return await self._dock(self.aid, unit)

    async def _undock_op(self) -> bool:
        return await self._undock(self.aid)

    async def _unit_hal(self, unit: str) -> MirroredUnitHAL:
        """The docked unit's HAL: its OPC UA interface, mirrored into this simulation."""
        from transfertwin.cps.opcua import OpcUaUnitHAL

        session = await self.node.peers.session(unit)
        loop = asyncio.get_running_loop()
        return MirroredUnitHAL(OpcUaUnitHAL(session, loop, timeout_s=10), self.env.system.tu, loop)

    async def _transfer(self, tm: str, unit: str, direction):
        from transfertwin.study.experiment import scene_controller

        hal = await self._unit_hal(unit)
        system = self.env.system
        camera = self.node.floor.operation.sensor == "camera" and direction.name == "TM_TO_TU"

        def run():  # one thread: the camera's GL context is current in the thread that made it
            vision = self._open_camera() if camera else None
            try:
                ctl = scene_controller(self.env.scene, system.tm, hal, vision or system,
                                       self.env.clock)  # fmt: skip
                return ctl.transfer(direction, self._face, None)
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

        load = (self.op or {}).get("load") or {}
        xy = POSITIONS[str(load.get("conveyor", "both"))]
        seed = zlib.crc32(f"{self._op_id}:{self._attempt}".encode())
        return open_sensor(self.env.system, expected_xy=xy,
                           theta_rad=math.radians(float(load.get("theta_deg", 0.0))),
                           seed=seed)  # fmt: skip

    async def _take_back(self, unit: str, to_unit: bool = False) -> bool:
        """Reverse both belt pairs (the unit's through its interface) in the simulation
        until the object is back (`cps.apps._hand_over.take_back`)."""
        from transfertwin.cps.apps import take_back

        hal = await self._unit_hal(unit)
        system = self.env.system

        def reverse() -> bool:
            with self.env.lock:
                return take_back(system.tm, hal, system.observe, self.env.clock,
                                 self.env.scene, to_unit)  # fmt: skip

        return await asyncio.to_thread(reverse)

    async def _moved(self, obj: str, holder: str) -> None:
        own = set(self.state.data["possesses"])
        own.add(obj) if holder == self.aid else own.discard(obj)
        self.state.data["possesses"] = sorted(own)
        self.state.save()
        await self.set("PossessedObjects", ",".join(self.state.data["possesses"]))
        self._report(self._op_id, {"event": "moved", "object": obj, "holder": holder})


#: Standard deviations PropS is told for a unit camera's ChArUco docking measurement:
#: about twice the spread measured on this rig with 3 grey levels of pixel noise (0.05 mm,
#: 0.2 mrad; docs/architecture.md, "PropS in the loop").
CAMERA_SIGMA_XY_M = 1e-4
CAMERA_SIGMA_THETA_RAD = 5e-4


@functools.cache
def _charuco_rig():
    from transfertwin.navigation import CharucoRig

    return CharucoRig(pixel_noise_sd=3.0)


def _observe_docking(robot, error, seed: int):
    """What is sensed at a docking: the module's own localisation fix of its world pose
    (x, y, θ, σ_xy, σ_θ) and the unit camera's ChArUco measurement of the docking error
    (x, y, θ; None when the board is not found)."""
    from transfertwin.navigation import localise

    rng = np.random.default_rng(np.random.SeedSequence([seed, 11]))
    noise = robot.cfg.noise
    own = localise(robot.pose, noise, rng)
    truth = np.array([error.x_m, error.y_m, error.theta_rad])
    seen = _charuco_rig().measure_error(truth, rng)
    return ((*(float(v) for v in own), noise.loc_xy_sd_m, noise.loc_theta_sd_rad),
            None if seen is None else tuple(float(v) for v in seen))  # fmt: skip


def _mm_deg(x: float, y: float, theta: float) -> dict[str, float]:
    return {"x_mm": round(x * 1e3, 4), "y_mm": round(y * 1e3, 4),
            "theta_deg": round(math.degrees(theta), 4)}  # fmt: skip


async def _props_docking_estimate(role, tm: str, unit: str, error, observed,
                                  measured: str = "true"):  # fmt: skip
    """PropS in the loop: report the module's pose and the unit camera's observation
    (`observed()`, run in a worker thread: (x, y, θ, σ_xy, σ_θ), and (x, y, θ) or None) to
    PropS, and take the docking error from its fused estimate (with its uncertainty). On
    the emulated plant the physics docks with the true error (it is the reality; the
    estimate is what the twin knows). Without PropS on the floor, or when it does not
    answer, `error` (recorded as `measured`: the true one, or the module's localisation's
    on real hardware), and why."""
    from transfertwin.sim import DockingError

    props = next((d.asset_id for d in role.node.descriptors.values()
                  if d.asset_class == "props"), None)  # fmt: skip
    if props is None:
        return error, None
    own, seen = await asyncio.to_thread(observed)
    info: dict[str, Any] = {measured: _mm_deg(error.x_m, error.y_m, error.theta_rad),
                            "camera": seen is not None}  # fmt: skip
    try:
        await asyncio.wait_for(role.node.peers.call(props, "ReportPose", tm, tm, *own), 10.0)
        if seen is not None:
            await asyncio.wait_for(role.node.peers.call(
                props, "ReportRelativePose", f"{unit}/camera", tm, unit, *seen,
                CAMERA_SIGMA_XY_M, CAMERA_SIGMA_THETA_RAD), 10.0)  # fmt: skip
        est = json.loads(await asyncio.wait_for(
            role.node.peers.call(props, "DockingError", tm, unit), 10.0))  # fmt: skip
        fused = DockingError(est["x_m"], est["y_m"], est["theta_rad"])
    except Exception as exc:  # PropS away, or an estimate outside the dockable range
        log.info("%s: docking error from PropS not available (%s); the %s one", tm, exc,
                 measured)  # fmt: skip
        return error, {**info, "used": measured, "why": f"{type(exc).__name__}: {exc}"}
    info["fused"] = {**_mm_deg(fused.x_m, fused.y_m, fused.theta_rad),
                     "sd_x_mm": round(est["sd_x_m"] * 1e3, 4),
                     "sd_y_mm": round(est["sd_y_m"] * 1e3, 4),
                     "sd_theta_deg": round(math.degrees(est["sd_theta_rad"]), 4)}  # fmt: skip
    if role.node.cfg.hal.kind == "plant":
        return error, {**info, "used": "true (the plant's physics)"}
    return fused, {**info, "used": "fused"}


def _warm_up() -> None:
    """Fit the docking-error generator once (about 0.6 s) before the first operation."""
    from transfertwin.cps.apps import docking_model

    docking_model()


def _make_transport():
    from transfertwin.cps.apps import HandOverRetries, VirtualTransport

    class ModuleTransport(HandOverRetries, VirtualTransport):
        """The skills of `VirtualTransport` with the hand-over policy (`HandOverRetries`:
        a failed transfer taken back and tried again); a module that
        restarted with an object on board puts it back on its belts in the simulation
        before docking to deliver it."""

        def _seed(self, leg):
            return super()._seed(leg) + 7919 * self.attempt

        async def dock(self, leg):
            env = self.cps.env
            if leg.name != "pick-up" and env.object_ref != self.obj:
                await asyncio.to_thread(self.cps._locked, _load_on_module, env, self.obj)
            return await super().dock(leg)

    return ModuleTransport


def _ModuleTransport(*args):
    return _make_transport()(*args)


def _load_on_module(env, obj: str) -> None:
    """Put `obj` on the module's belts in the simulation (after a restart of the module)."""
    from transfertwin.sim import DockingError

    system = env.use(obj)
    system.reset(DockingError(0.0, 0.0, 0.0))
    system.place("front", 0.0, -0.2, 0.0)
    system.clock.wait(env.scene.placement.settle_time_s)
    env.docked_unit = None
