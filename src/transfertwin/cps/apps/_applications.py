"""The application layers of the demo CPS's assets (Fig. 3.2, Sec. 5.1–5.2).

What each asset's OPC UA operations do: the transfer units' belt drives and possession
(external sync of a D/E asset), the transport module's docking and transport tasks (the flow
of Fig. 5.9a, `_transport.run_transport_operation`, with the virtual module's skills in
`VirtualTransport`; it drives a docked unit only through its OPC UA interface), and the
logical assets: the Transport Module System, the Experiment Manager, PropS and the
knowledge graph.

The Transport Module System keeps the `ObjectLedger` (where every object is, which
operation holds it): an order is checked and its object reserved when it is submitted, so
a refusal reaches the caller at once with its reason; accepted operations wait for an idle
transport module. Each completed transfer moves the object in the ledger, in the objects'
AAS (``PossessedBy``), in the transfer units' ``PossessedObjects`` and in the knowledge
graph (``tt:locatedAt``, ``tt:possesses``). After a failed pick-up the object stays at
the source; after a failed delivery it stays on the transport module (an operator has to
take it off: no order can name a transport module as source).

`AssetApplications` is a mixin of `Cps`; it uses the runtime's `assets`, `env`, `kg`,
`poses`, `config`, `ledger`, `completed`, `operations`, `floor_robots`, `client()` and
`_spawn()`.
"""

from __future__ import annotations

import asyncio
import json
import logging
from collections.abc import Awaitable, Callable

from transfertwin._errors import InputError
from transfertwin.control import TransferRecord
from transfertwin.cps.aas import AssetDescriptor
from transfertwin.cps.apps._props import PoseObservation
from transfertwin.cps.apps._transport import (
    Leg,
    StepResult,
    form_ots,
    legs_of,
    run_transport_operation,
    transfer_step,
)
from transfertwin.cps.opcua import AssetServer, OpcUaUnitHAL, OperationRefused
from transfertwin.ots import BeltThresholds, TransferDirection
from transfertwin.perception import (
    AABB,
    CameraIntrinsics,
    DepthCamera,
    Workspace,
    ground_truth_aabb,
    workspace_scan,
)
from transfertwin.study.experiment import (
    ExperimentSpec,
    experiment_seeds,
    run_experiment,
    scene_controller,
)

__all__ = ["AssetApplications", "VirtualTransport"]

log = logging.getLogger("transfertwin.cps")


class AssetApplications:
    """Operation handlers of every asset class (mixed into `Cps`)."""

    # -- handlers -------------------------------------------------------------------------
    def _handlers(self, desc: AssetDescriptor) -> dict[str, Callable[..., Awaitable[object]]]:
        aid, cls = desc.asset_id, desc.asset_class
        if cls == "transfer_unit":
            return {"SetBeltSpeed": lambda b, v: self._set_belt(aid, b, v),
                    "SetPossessedObjects": lambda objs: self._set_possessed(aid, objs)}  # fmt: skip
        if cls == "transport_module":
            return {"SetBeltSpeed": lambda b, v: self._set_belt(aid, b, v),
                    "QueueTransportTask": lambda s, t, o: self._queue_task(aid, s, t, o),
                    "Dock": lambda unit: self._dock(aid, unit),
                    "Undock": lambda: self._undock(aid)}  # fmt: skip
        if cls == "transport_module_system":
            return {"SubmitTransportOperation": self._submit,
                    "OperationStatus": self._operation_status}  # fmt: skip
        if cls == "experiment_manager":
            return {"RunExperiment": self._run_experiment}
        if cls == "props":
            return {"ReportPose": self._report_pose, "FusedPose": self._fused_pose}
        if cls == "knowledge_graph":
            return {"Query": self._query}
        return {}

    async def _set_belt(self, aid: str, belt: str, speed: float) -> bool:
        if belt not in ("left", "right"):
            raise ValueError(f"unknown belt {belt!r}")
        with self.env.lock:
            if self.env.object_ref is not None:
                if aid == "TM_1":
                    self.env.system.tm.set_belt_speed(belt, speed)
                elif aid == self.env.docked_unit:
                    self.env.system.tu.set_belt_speed(belt, speed)
        server = self.assets[aid].server
        await server.set("OperationalData", f"BeltSpeed{belt.capitalize()}", float(speed))
        return True

    def _sync_barriers(self, system, docked: str | None) -> None:
        """After each step the docked unit publishes its own light barriers (internal sync)."""
        if docked is None or self._loop is None:
            return
        barriers = system.tu.barriers()
        publish = self._publish_barriers(self.assets[docked].server, barriers)
        try:
            on_loop = asyncio.get_running_loop() is self._loop
        except RuntimeError:
            on_loop = False
        if on_loop:  # stepping on the event loop itself (never while a controller runs)
            self._spawn(publish)
        else:  # a controller thread: publish before it reads the barriers
            asyncio.run_coroutine_threadsafe(publish, self._loop).result(10)

    @staticmethod
    async def _publish_barriers(server: AssetServer, barriers: dict[str, bool]) -> None:
        await server.set("OperationalData", "BarrierNearInterrupted", barriers["near"])
        await server.set("OperationalData", "BarrierFarInterrupted", barriers["far"])

    async def _set_possessed(self, aid: str, objects: str) -> bool:
        ids = [o for o in objects.split(",") if o]
        await self.assets[aid].server.set("OperationalData", "PossessedObjects", ",".join(ids))
        self.kg.set_possesses(aid, ids)
        return True

    async def _dock(self, tm: str, unit: str) -> bool:
        if unit not in self.assets or self.assets[unit].desc.asset_class != "transfer_unit":
            raise ValueError(f"no transfer unit {unit!r}")
        await self.assets[tm].server.set("OperationalData", "DockedAt", unit)
        await self.assets[unit].server.set("OperationalData", "DockedTransportModule", tm)
        self.kg.set_docked(tm, unit)
        return True

    async def _undock(self, tm: str) -> bool:
        unit = await self.assets[tm].server.get("OperationalData", "DockedAt")
        if unit:
            await self.assets[unit].server.set("OperationalData", "DockedTransportModule", "")
        await self.assets[tm].server.set("OperationalData", "DockedAt", "")
        self.kg.set_docked(tm, None)
        return True

    # -- transport operations -----------------------------------------------------------------
    async def _submit(self, source: str, target: str, obj: str) -> str:
        """TMS: check the order against the ledger, reserve the object, queue the operation.

        Check and reservation happen without an await in between, so concurrent orders
        for one object cannot both be accepted.
        """
        online = [a for a in self.kg.assets(online_only=True) if a["class"] == "transport_module"]
        if not online:
            raise OperationRefused("no transport module is online", status="BadResourceUnavailable")
        self.ledger.check(source, target, obj)  # refused orders take no operation id
        op_id = f"op{next(self._ops)}"
        self.ledger.reserve(op_id, source, target, obj)
        self.operations[op_id] = {"operation": op_id, "state": "queued", "source": source,
                                  "target": target, "object": obj}  # fmt: skip
        tms = self.assets["TMS"].server
        await tms.set("OperationalData", "QueuedOperations",
                      await tms.get("OperationalData", "QueuedOperations") + 1)  # fmt: skip
        log.info("TMS: %s %s -> %s (%s) accepted", op_id, source, target, obj)
        self._spawn(self._execute(op_id, source, target, obj))
        return op_id

    async def _operation_status(self, op_id: str) -> str:
        """TMS: an operation's state ('queued', 'running', 'finished') and result."""
        if op_id not in self.operations:
            raise OperationRefused(f"no operation {op_id!r}", argument="operation_id")
        return json.dumps(self.operations[op_id])

    async def _allocate(self) -> str:
        """Wait for an idle transport module (from the graph) and claim it."""
        async with self._tm_free:
            while True:
                idle = [t for t in self.kg.idle_transport_modules() if t not in self._claimed]
                if idle:
                    self._claimed.add(idle[0])
                    return idle[0]
                await self._tm_free.wait()

    async def _execute(self, op_id: str, source: str, target: str, obj: str) -> None:
        """Run one accepted operation to its end; never raises (the caller is a task)."""
        tms = self.assets["TMS"].server
        record = self.operations[op_id]
        try:
            tm = await self._allocate()
            record.update(state="running", tm=tm)
            log.info("TMS: %s allocated to %s", op_id, tm)
            try:
                async with self.client(tm) as session:
                    result = json.loads(await session.call("QueueTransportTask", source,
                                                           target, obj))  # fmt: skip
            finally:
                self._claimed.discard(tm)
                async with self._tm_free:
                    self._tm_free.notify_all()
        except asyncio.CancelledError:
            raise
        except Exception as exc:  # reported as the operation's result, logged in full
            log.exception("TMS: %s failed", op_id)
            result = {"status": f"error: {type(exc).__name__}: {exc}"}
        finally:
            self.ledger.release(op_id, obj)
        record.update(state="finished", result=result, location=self.ledger.location(obj))
        self.completed.append(record)
        await tms.set("OperationalData", "QueuedOperations",
                      await tms.get("OperationalData", "QueuedOperations") - 1)  # fmt: skip
        await tms.set("OperationalData", "CompletedOperations", len(self.completed))
        log.info("TMS: %s finished: %s; %s is at %s", op_id, result["status"], obj,
                 record["location"])  # fmt: skip

    async def _queue_task(self, tm: str, source: str, target: str, obj: str) -> str:
        """TM_1 application layer: fetch `obj` at `source`, deliver it to `target` (Fig. 5.9a)."""
        server = self.assets[tm].server
        if (state := await server.get("OperationalData", "State")) != "idle":
            raise OperationRefused(f"{tm} is {state}", status="BadInvalidState")
        at = self.ledger.locations().get(obj)  # the TMS reserved it; the TM checks the place
        if at is None:
            raise OperationRefused(f"{obj!r} is not an object of this CPS", argument="object")
        if at != source:
            raise OperationRefused(f"{obj} is at {at}, not at {source}", status="BadInvalidState",
                                   argument="source")  # fmt: skip
        await server.set("OperationalData", "CurrentTask", f"{obj}: {source} -> {target}")

        async def on_state(state: str, leg: Leg | None) -> None:
            await server.set("OperationalData", "State", state)
            self.kg.set_state(tm, state)
            if leg is not None:
                log.info("%s: %s (%s at %s)", tm, state, leg.name, leg.unit)

        skills = VirtualTransport(self, tm, source, target, obj)
        try:
            result = await run_transport_operation(skills, legs_of(source, target), on_state)
        finally:
            await server.set("OperationalData", "State", "idle")
            await server.set("OperationalData", "CurrentTask", "")
            self.kg.set_state(tm, "idle")
        result["docking"] = self.config.docking
        if result["failed_step"] is not None:
            log.info("%s: %s failed while %s: %s", tm, result["status"].split(" at ")[-1],
                     result["failed_step"], result["reason"])  # fmt: skip
        return json.dumps(result)

    async def _publish_pose(self, tm: str) -> None:
        """Publish the transport module's floor pose (PoseX, PoseY, PoseTheta)."""
        x, y, theta = (float(v) for v in self.floor_robots[tm].pose)
        server = self.assets[tm].server
        for prop, value in (("PoseX", x), ("PoseY", y), ("PoseTheta", theta)):
            await server.set("OperationalData", prop, value)

    async def _moved(self, obj: str, holder: str) -> None:
        """A transfer put `obj` onto `holder`: update the ledger, both holders' possessions
        (transfer units through their OPC UA interface: external sync), the object's AAS
        and the knowledge graph."""
        previous = self.ledger.move(obj, holder)
        await self._publish_location(obj, previous, holder)

    async def _publish_location(self, obj: str, *holders: str) -> None:
        for holder in dict.fromkeys(holders):
            objects = ",".join(self.ledger.objects_at(holder))
            if self.assets[holder].desc.asset_class == "transfer_unit":
                await self._call(holder, "SetPossessedObjects", objects)
            else:
                await self._set_possessed(holder, objects)
        location = self.ledger.location(obj)
        if obj in self.assets:
            await self.assets[obj].server.set("OperationalData", "PossessedBy", location)
            self.kg.set_location(obj, location)

    async def _docking_estimate(self, tm: str, unit: str, error, seed: int):
        """The docking error the transfer uses, and what PropS said of it (None here: the
        single-process CPS docks with the true error; a module's process asks PropS)."""
        return error, None

    def _error(self, source: str, target: str, obj: str, leg: int):
        seed, _ = experiment_seeds(self.config.seed, f"{obj}:{source}:{target}", leg, 0)
        return self._docking.sample(seed)

    def _locked(self, fn: Callable[..., object], *args: object) -> object:
        with self.env.lock:
            return fn(*args)

    async def _call(self, aid: str, operation: str, *args: object) -> object:
        async with self.client(aid) as session:
            return await session.call(operation, *args)

    async def _transfer(self, tm: str, unit: str, direction: TransferDirection) -> TransferRecord:
        """One OTS between the TM (local HAL) and `unit` (over OPC UA)."""
        scene = self.config.scene
        async with self.client(unit) as session:
            remote = OpcUaUnitHAL(session, asyncio.get_running_loop(), timeout_s=30)
            system = self.env.system
            ctl = scene_controller(scene, system.tm, remote, system, self.env.clock)
            return await asyncio.to_thread(ctl.transfer, direction, "front", None)

    # -- experiment manager, PropS, knowledge graph ----------------------------------------
    async def _run_experiment(
        self, unit: str, obj: str, face: str, conveyor: str, theta_deg: int, seed: int
    ) -> str:
        """EM: run E^V against `unit` through its OPC UA interface."""
        spec = ExperimentSpec(obj, face, conveyor, int(theta_deg), scene=self.config.scene,
                              seed=int(seed))  # fmt: skip
        async with self.client(unit) as session:
            remote = OpcUaUnitHAL(session, asyncio.get_running_loop(), timeout_s=30)
            with self.env.lock:
                self.env.use(obj)
                self.env.docked_unit = unit
                try:
                    result = await asyncio.to_thread(run_experiment, spec, tu_hal=remote)
                finally:
                    self.env.docked_unit = None
        return json.dumps(result.row())

    async def _report_pose(self, source, subject, x, y, theta, sigma_xy, sigma_theta) -> bool:
        self.poses.add(PoseObservation(source, subject, x, y, theta, sigma_xy, sigma_theta))
        await self.assets["PropS"].server.set("OperationalData", "FusedPoses",
                                              len(self.poses.solve()))  # fmt: skip
        return True

    async def _fused_pose(self, subject: str) -> str:
        try:
            pose = self.poses.fused(subject)
        except InputError as exc:
            raise ValueError(str(exc)) from None
        return json.dumps({"x": pose.x, "y": pose.y, "theta": pose.theta})

    async def _query(self, sparql: str) -> str:
        return json.dumps(self.kg.query(sparql))


#: Depth image size of the workspace scan when forming the OTS (the perception benchmarks'
#: size: enough for a core's box within a centimetre or two, ~0.5 s per scan).
SCAN_SIZE = (160, 120)


def _load_args(state: dict[str, object] | None) -> tuple[str, float, float]:
    """(face, θ deg, lateral offset m) that put an object on a unit's belts so that it
    crosses onto the module in `state`: the conveyor's lateral position of the study's
    states (Eq. 6.3), the unit's belts being in line with the module's."""
    from transfertwin.ots import POSITIONS

    if not state:
        return "front", 0.0, 0.0
    return (str(state["face"]), float(state["theta_deg"]),
            float(POSITIONS[str(state["conveyor"])][1]))  # fmt: skip


class VirtualTransport:
    """The virtual transport module's skills (`TransportSkills`) in the demo CPS.

    With ``CpsConfig.docking == 'navigated'`` the module drives on the shop floor
    (`FloorRobot`), docks with the error that emerges there and forms the OTS from its
    depth camera's workspace scan; with 'sampled' it is put at the station with an error
    drawn from the fitted generator and forms the OTS from the simulation's true box.
    """

    #: The pre-transfer state the object is loaded in at the source ({face, conveyor,
    #: theta_deg}; None: front face, θ = 0, centred, as the demo always did).
    load_state: dict[str, object] | None = None
    #: The module's depth camera forms the OTS and checks the ledger (floor: sensor =
    #: "camera"); the face the object lies on, for that check.
    camera: bool = False
    face: str = "front"
    #: Heights the camera has learnt ('o10/front' -> m; `cps.apps._camera`), None: none kept.
    heights: dict[str, float] | None = None

    def __init__(self, cps: AssetApplications, tm: str, source: str, target: str, obj: str):
        self.cps, self.tm, self.obj = cps, tm, obj
        self.source, self.target = source, target
        self.robot = cps.floor_robots[tm]
        self.navigated = cps.config.docking == "navigated"

    def _seed(self, leg: Leg) -> int:
        cfg = self.cps.config
        seed, _ = experiment_seeds(cfg.seed, f"{self.obj}:{self.source}:{self.target}",
                                   leg.index, 0)  # fmt: skip
        return seed

    def _station(self, leg: Leg) -> str:
        station = self.cps.assets[leg.unit].desc.station
        if station is None:
            raise ValueError(f"{leg.unit} stands at no station of the shop floor")
        return station

    async def navigate(self, leg: Leg) -> StepResult:
        station = self._station(leg)
        if not self.navigated:
            return StepResult(True, info={"station": station})
        res = await asyncio.to_thread(self.robot.navigate, station, self._seed(leg))
        await self.cps._publish_pose(self.tm)
        info = {"station": station, "path_m": round(res.path_m, 3),
                "drive_s": round(res.drive_s, 2)}  # fmt: skip
        return StepResult(res.status == "ok", res.reason, info)

    async def dock(self, leg: Leg) -> StepResult:
        cps, station = self.cps, self._station(leg)
        if self.navigated:
            res = await asyncio.to_thread(self.robot.dock, station)
        else:
            err = cps._error(self.source, self.target, self.obj, leg.index)
            res = self.robot.teleport_dock(station, err)
        await cps._publish_pose(self.tm)
        info = {k: v for k, v in res.as_dict().items() if k not in ("path_m", "reason")}
        if res.status != "ok":
            return StepResult(False, f"docking at {leg.unit}: {res.reason}", info)
        err, env = res.docking_error(), cps.env
        err, props = await cps._docking_estimate(self.tm, leg.unit, err, self._seed(leg))
        if props is not None:
            info["props"] = props
        if leg.name == "pick-up":  # the object lies on the source unit's belts
            await asyncio.to_thread(cps._locked, env.load_object_at_unit, self.obj, leg.unit, err,
                                    *_load_args(self.load_state))  # fmt: skip
        else:
            await asyncio.to_thread(cps._locked, env.dock, leg.unit, err)
        await cps._dock(self.tm, leg.unit)
        log.info("%s: docked at %s, docking error %s", self.tm, leg.unit,
                 tuple(round(v, 2) for v in err.as_mm_deg()))  # fmt: skip
        return StepResult(True, info=info)

    def _scan(self, seed: int) -> list[AABB]:
        scene, system = self.cps.config.scene, self.cps.env.system
        workspace = Workspace.for_layout(scene.layout, scene.gap_m, docked=True)
        size = CameraIntrinsics(*SCAN_SIZE)
        with DepthCamera(system.model, system.data, intrinsics=size) as camera:
            detection, _ = workspace_scan(camera, workspace, seed=seed)
        return list(detection.boxes)

    async def form_ots(self, leg: Leg) -> StepResult:
        cps = self.cps
        seeing = self.navigated or self.camera
        if seeing:
            boxes = await asyncio.to_thread(cps._locked, self._scan, self._seed(leg))
        else:
            boxes = [cps._locked(ground_truth_aabb, cps.env.system)]
        info = {"source": "depth camera" if seeing else "ground truth",
                "boxes": [b.as_dict() for b in boxes]}  # fmt: skip
        if self.camera:  # what it sees against what the ledger says (Sec. 5.5)
            from transfertwin.cps.apps._camera import height_key, scan_check

            verdict = scan_check(
                boxes, self.obj, self.face, self.tm, leg.unit,
                leg.direction is TransferDirection.TU_TO_TM, cps.config.scene.gap_m,
                self.heights)  # fmt: skip
            info["possessions"] = verdict.summary
            if not verdict.ok:
                log.info("%s: scanned %s and itself: %s", self.tm, leg.unit, verdict.why)
                return StepResult(False, verdict.why, info)
            if verdict.height_m is not None and self.heights is not None:
                self.heights[height_key(self.obj, self.face)] = round(verdict.height_m, 4)
                log.info("%s: learnt %s", self.tm, verdict.summary["learnt"][0])
        # The transport module carries objects only on its belts; a unit's representation
        # also lists what its station holds off the belts, so for a unit the scan decides.
        pickup = leg.direction is TransferDirection.TU_TO_TM
        holds = cps.ledger.objects_at(self.tm) if pickup else []
        check = form_ots(
            boxes, leg.direction, BeltThresholds(t_max=cps.config.scene.t_max_s),
            obj=self.obj, tm=self.tm, unit=leg.unit, receiver_holds=holds,
        )  # fmt: skip
        log.info("%s: scanned %s and itself: %d object(s) seen%s", self.tm, leg.unit,
                 len(boxes), "" if check.ok else f"; no OTS: {check.reason}")  # fmt: skip
        return StepResult(check.ok, check.reason, info)

    async def transfer(self, leg: Leg) -> StepResult:
        rec = await self.cps._transfer(self.tm, leg.unit, leg.direction)
        if leg.name == "pick-up":
            log.info("%s: took %s from %s: y = %d", self.tm, self.obj, leg.unit, rec.y)
        else:
            log.info("%s: handed %s to %s: y = %d", self.tm, self.obj, leg.unit, rec.y)
        return transfer_step(rec)

    async def resolve(self, leg: Leg, success: bool) -> None:
        cps = self.cps
        if success:
            await cps._moved(self.obj, self.tm if leg.name == "pick-up" else leg.unit)
        await cps._undock(self.tm)
        with cps.env.lock:
            cps.env.undock()
