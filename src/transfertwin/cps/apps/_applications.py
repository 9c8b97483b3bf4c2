"""The application layers of the demo CPS's assets (Fig. 3.2, Sec. 5.1–5.2).

What each asset's OPC UA operations do: the transfer units' belt drives and possession
(external sync of a D/E asset), the transport module's docking and transport tasks (which
drive a docked unit only through its OPC UA interface), and the logical assets: the
Transport Module System, the Experiment Manager, PropS and the knowledge graph.

`AssetApplications` is a mixin of `Cps`; it uses the runtime's `assets`, `env`, `kg`,
`poses`, `config`, `completed`, `client()` and `_spawn()`.
"""

from __future__ import annotations

import asyncio
import json
import logging
from collections.abc import Awaitable, Callable

from transfertwin._errors import InputError
from transfertwin.cps.aas import AssetDescriptor
from transfertwin.cps.apps._props import PoseObservation
from transfertwin.cps.opcua import AssetServer, OpcUaUnitHAL
from transfertwin.ots import TransferDirection
from transfertwin.study.experiment import (
    ExperimentSpec,
    experiment_seeds,
    run_experiment,
    scene_controller,
)

__all__ = ["AssetApplications"]

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
            return {"SubmitTransportOperation": self._submit}
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
        """TMS: allocate the operation to an idle transport module (from the graph)."""
        for unit in (source, target):
            if unit not in self.assets or self.assets[unit].desc.asset_class != "transfer_unit":
                raise ValueError(f"no transfer unit {unit!r}")
        idle = self.kg.idle_transport_modules()
        if not idle:
            raise ValueError("no idle transport module")
        op_id = f"op{next(self._ops)}"
        tms = self.assets["TMS"].server
        await tms.set("OperationalData", "QueuedOperations",
                      await tms.get("OperationalData", "QueuedOperations") + 1)  # fmt: skip
        log.info("TMS: %s %s -> %s (%s) allocated to %s", op_id, source, target, obj, idle[0])
        self._spawn(self._execute(op_id, idle[0], source, target, obj))
        return op_id

    async def _execute(self, op_id: str, tm: str, source: str, target: str, obj: str) -> None:
        tms = self.assets["TMS"].server
        async with self.client(tm) as session:
            result = await session.call("QueueTransportTask", source, target, obj)
        record = {"operation": op_id, "tm": tm, "source": source, "target": target,
                  "object": obj, "result": json.loads(result)}  # fmt: skip
        self.completed.append(record)
        await tms.set("OperationalData", "QueuedOperations",
                      await tms.get("OperationalData", "QueuedOperations") - 1)  # fmt: skip
        await tms.set("OperationalData", "CompletedOperations", len(self.completed))
        log.info("TMS: %s finished: %s", op_id, record["result"]["status"])

    async def _queue_task(self, tm: str, source: str, target: str, obj: str) -> str:
        """TM_1 application layer: fetch `obj` at `source`, deliver it to `target`."""
        server = self.assets[tm].server
        await server.set("OperationalData", "State", "busy")
        await server.set("OperationalData", "CurrentTask", f"{obj}: {source} -> {target}")
        self.kg.set_state(tm, "busy")
        try:
            result = await self._transport(tm, source, target, obj)
        finally:
            await server.set("OperationalData", "State", "idle")
            await server.set("OperationalData", "CurrentTask", "")
            self.kg.set_state(tm, "idle")
        return json.dumps(result)

    def _error(self, source: str, target: str, obj: str, leg: int):
        seed, _ = experiment_seeds(self.config.seed, f"{obj}:{source}:{target}", leg, 0)
        return self._docking.sample(seed)

    async def _transport(self, tm: str, source: str, target: str, obj: str) -> dict:
        env = self.env
        err1 = self._error(source, target, obj, 0)
        await asyncio.to_thread(self._locked, env.load_object_at_unit, obj, source, err1)
        await self._dock(tm, source)
        log.info("%s: docked at %s, docking error %s", tm, source,
                 tuple(round(v, 2) for v in err1.as_mm_deg()))  # fmt: skip
        y1 = await self._transfer(tm, source, TransferDirection.TU_TO_TM)
        log.info("%s: took %s from %s: y = %d", tm, obj, source, y1)
        if y1 != 1:
            return {"status": "failed at pick-up", "y_pickup": y1}
        await self._call(source, "SetPossessedObjects", "")
        await self._set_possessed(tm, obj)
        await self._undock(tm)
        err2 = self._error(source, target, obj, 1)
        await asyncio.to_thread(self._locked, env.dock, target, err2)
        await self._dock(tm, target)
        log.info("%s: docked at %s, docking error %s", tm, target,
                 tuple(round(v, 2) for v in err2.as_mm_deg()))  # fmt: skip
        y2 = await self._transfer(tm, target, TransferDirection.TM_TO_TU)
        log.info("%s: handed %s to %s: y = %d", tm, obj, target, y2)
        if y2 == 1:
            await self._set_possessed(tm, "")
            await self._call(target, "SetPossessedObjects", obj)
        await self._undock(tm)
        with env.lock:
            env.undock()
        return {"status": "delivered" if y2 == 1 else "failed at delivery",
                "y_pickup": y1, "y_delivery": y2}  # fmt: skip

    def _locked(self, fn: Callable[..., object], *args: object) -> object:
        with self.env.lock:
            return fn(*args)

    async def _call(self, aid: str, operation: str, *args: object) -> object:
        async with self.client(aid) as session:
            return await session.call(operation, *args)

    async def _transfer(self, tm: str, unit: str, direction: TransferDirection) -> int:
        """One OTS between the TM (local HAL) and `unit` (over OPC UA)."""
        scene = self.config.scene
        async with self.client(unit) as session:
            remote = OpcUaUnitHAL(session, asyncio.get_running_loop(), timeout_s=30)
            system = self.env.system
            ctl = scene_controller(scene, system.tm, remote, system, self.env.clock)
            record = await asyncio.to_thread(ctl.transfer, direction, "front", None)
        return record.y

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
