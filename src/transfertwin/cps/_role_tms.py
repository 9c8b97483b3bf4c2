"""The Transport Module System in its own process: the owner of the object ledger and of
the operations (docs/architecture.md, "Deployment").

An order is checked against the ledger and its object reserved in one step; it gets an id
that is unique on the floor across restarts (the counter is persisted), then waits for an
idle transport module that the knowledge graph lists as online. The module reports every
step, every moved object and the result (`ReportProgress`); the TMS writes each report to
its state file before it acknowledges it, so a report is applied exactly once whatever
crashes.

Faults: a module whose lease expires while it holds an operation fails that operation with
the step it was in. A failure in the middle of a transfer leaves the object's place
unknown: the ledger then says ``unknown, last seen at X`` with the operation that lost it,
orders for it are refused until an operator states where it is (`Locate`) or a late report
of the module settles it. Nothing is dropped: a report for an operation that has already
ended still moves the object, and is kept in the operation's history.
"""

from __future__ import annotations

import asyncio
import json
import logging
import time
from typing import TYPE_CHECKING, Any

from transfertwin.cps._roles import Role

if TYPE_CHECKING:
    from transfertwin.cps._node import AssetNode

__all__ = ["TmsRole"]

log = logging.getLogger("transfertwin.cps")


class TmsRole(Role):
    """The Transport Module System."""

    def __init__(self, node: AssetNode) -> None:
        super().__init__(node)
        from transfertwin.cps.apps import ObjectLedger

        data = self.state.data
        modules = [m.asset_id for m in node.floor.modules]
        self.ledger = ObjectLedger(data["locations"], node.floor.units, modules)
        self.ops: dict[str, dict[str, Any]] = data["operations"]
        for op in self.ops.values():
            if op["state"] != "finished":
                self.ledger.hold(op["operation"], op["object"])
        self._claimed: dict[str, str] = {}  # module -> operation
        self._done: dict[str, asyncio.Event] = {}
        self._pending: set[str] = set()  # holders/objects whose published location is stale

    def initial(self) -> dict[str, Any]:
        return {"next_op": 1, "locations": self.node.floor.placement(), "unknown": {},
                "operations": {}}  # fmt: skip

    def handlers(self) -> dict[str, Any]:
        return {"SubmitTransportOperation": self._submit, "OperationStatus": self._status,
                "ReportProgress": self._progress, "Ledger": self._ledger,
                "Locate": self._locate}  # fmt: skip

    async def start(self) -> None:
        self._pending |= set(self.node.floor.units) | {o for o, _ in self.node.floor.objects}
        for op_id, op in self.ops.items():
            if op["state"] != "finished":
                log.info("TMS: resuming %s (%s)", op_id, op["phase"])
                if op.get("module"):
                    self._claimed[op["module"]] = op_id
                self.node.spawn(self._execute(op_id))
        await self._counters()
        self.node.spawn(self._publisher())

    def _save(self) -> None:
        self.state.data["locations"] = self.ledger.locations()
        self.state.save()

    async def live(self) -> dict[str, Any]:
        running = sum(op["state"] != "finished" for op in self.ops.values())
        return {"state": "busy" if running else "idle"}

    # -- orders ---------------------------------------------------------------------------
    async def _submit(self, source: str, target: str, obj: str) -> str:
        from transfertwin.cps.opcua import OperationRefused

        unknown = self.state.data["unknown"].get(obj)
        if unknown is not None:
            raise OperationRefused(
                f"where {obj} is is unknown since {unknown['operation']} "
                f"(last seen at {unknown['last_seen']}); say where it is with "
                f"'transfertwin cps locate'", status="BadInvalidState", argument="object")
        modules = await self._modules()
        online = [m for m in modules or () if m["online"]]
        if modules is not None and not online:
            raise OperationRefused("no transport module is online",
                                   status="BadResourceUnavailable")  # fmt: skip
        if source in self.node.floor.units and online and all(m.get("possesses") for m in online):
            held = "; ".join(f"{m['id']} carries {', '.join(m['possesses'])}" for m in online)
            raise OperationRefused(f"every transport module carries an object ({held}): order "
                                   "those onward first", status="BadResourceUnavailable",
                                   argument="object")  # fmt: skip
        data = self.state.data
        op_id = f"op{data['next_op']}"
        self.ledger.reserve(op_id, source, target, obj)
        data["next_op"] += 1
        self.ops[op_id] = {"operation": op_id, "object": obj, "source": source,
                           "target": target, "state": "queued", "phase": "queued",
                           "module": None, "submitted": time.time(),
                           "history": [[time.time(), "queued"]]}  # fmt: skip
        self._save()
        log.info("TMS: %s %s -> %s (%s) accepted", op_id, source, target, obj)
        await self._counters()
        self.node.spawn(self._execute(op_id))
        return op_id

    async def _status(self, op_id: str) -> str:
        from transfertwin.cps.opcua import OperationRefused

        if op_id not in self.ops:
            raise OperationRefused(f"no operation {op_id!r}", argument="operation_id")
        return json.dumps(self.ops[op_id])

    async def _ledger(self) -> str:
        data = self.state.data
        return json.dumps({"locations": self.ledger.locations(), "unknown": data["unknown"],
                           "moving": self.ledger.moving(),
                           "operations": list(self.ops.values())})  # fmt: skip

    async def _locate(self, obj: str, holder: str) -> bool:
        if obj not in self.ledger.locations():
            raise ValueError(f"{obj!r} is not an object of this floor")
        if holder not in self.ledger.holders:
            raise ValueError(f"{holder!r} is no transfer unit or transport module of this floor")
        if obj in self.ledger.moving():
            raise ValueError(f"{obj} is being moved by {self.ledger.moving()[obj]}")
        self._move(obj, holder)
        log.info("TMS: an operator located %s at %s", obj, holder)
        return True

    def _move(self, obj: str, holder: str) -> None:
        previous = self.ledger.move(obj, holder)
        self.state.data["unknown"].pop(obj, None)
        self._save()
        self._pending |= {previous, holder, obj}

    # -- execution ------------------------------------------------------------------------
    async def _modules(self) -> list[dict[str, Any]] | None:
        """The transport modules as the knowledge graph knows them (None: graph away)."""
        try:
            status = json.loads(await asyncio.wait_for(self.node.peers.call("KG", "Status"), 5))
        except Exception as exc:
            log.debug("TMS: knowledge graph not answering: %s", exc)
            return None
        for a in status["assets"]:
            if a.get("address"):
                self.node.learn(a["id"], a["address"])
        return [a for a in status["assets"] if a.get("class") == "transport_module"]

    async def _allocate(self, op_id: str) -> str:
        """Wait for an online, idle transport module that holds no operation; claim it
        (the module the object lies on, for an order from a module onward). A module that
        carries an object takes no other order: objects travel one at a time."""
        source = self.ops[op_id]["source"]
        carrier = source if source not in self.node.floor.units else None
        while True:
            for m in await self._modules() or []:
                if carrier is not None and m["id"] != carrier:
                    continue
                if carrier is None and m.get("possesses"):
                    continue
                if m["online"] and m["state"] == "idle" and m["id"] not in self._claimed:
                    self._claimed[m["id"]] = op_id
                    return m["id"]
            await asyncio.sleep(0.5)

    async def _execute(self, op_id: str) -> None:
        from transfertwin.cps.opcua import OperationRefused

        op = self.ops[op_id]
        done = self._done.setdefault(op_id, asyncio.Event())
        while op["module"] is None:
            module = await self._allocate(op_id)
            try:
                await asyncio.wait_for(self.node.peers.call(
                    module, "AssignOperation", op_id, op["source"], op["target"], op["object"]),
                    15)  # fmt: skip
            except OperationRefused as exc:
                if module == op["source"] and exc.status == "BadInvalidState" and (
                        exc.argument == "object"):  # fmt: skip
                    # the ledger says the module carries it, the module says it does not
                    self._claimed.pop(module, None)
                    self._finish(op_id, {"status": "failed at delivery", "failed_step": "assigned",
                                         "reason": f"{exc.reason}: its place is not known",
                                         "location_unknown": True})  # fmt: skip
                    return
                log.info("TMS: %s not assigned to %s: %s", op_id, module, exc)
                self._claimed.pop(module, None)
                await asyncio.sleep(0.5)
                continue
            except (OSError, TimeoutError, ConnectionError) as exc:
                log.info("TMS: %s not assigned to %s: %s", op_id, module, exc)
                self._claimed.pop(module, None)
                await asyncio.sleep(0.5)
                continue
            op.update(module=module, state="running", phase="assigned")
            op["history"].append([time.time(), f"assigned to {module}"])
            self._save()
            log.info("TMS: %s allocated to %s", op_id, module)
        await self._watch(op_id, done)

    async def _watch(self, op_id: str, done: asyncio.Event) -> None:
        """Wait for the result; fail the operation if its module stays offline.

        A module whose lease expired may only have been slow: the operation fails once the
        module has been offline for one more lease period (a module that restarted reports
        the failure itself, with the step it was in).
        """
        op = self.ops[op_id]
        module = op["module"]
        grace = self.node.cfg.lease_s
        offline_since: float | None = None
        while op["state"] != "finished":
            try:
                await asyncio.wait_for(done.wait(), 1.0)
                continue
            except TimeoutError:
                pass
            modules = await self._modules()
            if modules is None:
                continue  # the graph is away: cannot tell, keep waiting
            if module in {m["id"] for m in modules if m["online"]}:
                offline_since = None
                continue
            offline_since = offline_since or time.monotonic()
            if time.monotonic() - offline_since >= grace and op["state"] != "finished":
                step = op["phase"]
                self._finish(op_id, {
                    "status": f"failed while {step}", "failed_step": step,
                    "reason": f"{module} went offline (lease expired) while {step}",
                    "location_unknown": step == "transferring",
                })  # fmt: skip

    def _finish(self, op_id: str, result: dict[str, Any]) -> None:
        op = self.ops[op_id]
        obj = op["object"]
        if result.get("location_unknown"):
            self.state.data["unknown"][obj] = {"last_seen": self.ledger.location(obj),
                                               "operation": op_id}  # fmt: skip
            self._pending |= {self.ledger.location(obj), obj}
        self.ledger.release(op_id, obj)
        ok = result.get("status") == "delivered"
        op.update(state="finished", phase="done" if ok else "failed", result=result,
                  location=self._where(obj), finished=time.time())  # fmt: skip
        op["history"].append([time.time(), op["phase"]])
        if op.get("module"):
            self._claimed.pop(op["module"], None)
        self._save()
        self._done.setdefault(op_id, asyncio.Event()).set()
        self.node.spawn(self._counters())
        log.info("TMS: %s finished: %s; %s is at %s", op_id, result.get("status"), obj,
                 op["location"])  # fmt: skip

    def _where(self, obj: str) -> str:
        unknown = self.state.data["unknown"].get(obj)
        if unknown is None:
            return self.ledger.location(obj)
        return f"unknown, last seen at {unknown['last_seen']}"

    async def _progress(self, op_id: str, payload: str) -> bool:
        """A module's report: applied once (the TMS saves it before acknowledging)."""
        event = json.loads(payload)
        op = self.ops.get(op_id)
        if op is None:
            raise ValueError(f"no operation {op_id!r}")
        kind = event.get("event")
        if kind == "moved":
            self._move(event["object"], event["holder"])
            op["history"].append([event.get("t", time.time()),
                                  f"{event['object']} onto {event['holder']}"])  # fmt: skip
        elif kind == "step" and op["state"] != "finished":
            op["phase"] = event["state"] if event["state"] != "idle" else op["phase"]
            op["history"].append([event.get("t", time.time()), event["state"]])
        elif kind == "result":
            if op["state"] == "finished":
                late = event["result"]
                op["history"].append([time.time(), f"late result: {late['status']}"])
                obj = op["object"]
                if (late.get("location_unknown") and obj not in self.ledger.moving()
                        and obj not in self.state.data["unknown"]):  # fmt: skip
                    # the module knows better than the lease did: the object may be in the gap
                    self.state.data["unknown"][obj] = {"last_seen": self.ledger.location(obj),
                                                       "operation": op_id}  # fmt: skip
                    self._pending |= {self.ledger.location(obj), obj}
            else:
                self._finish(op_id, event["result"])
                return True
        self._save()
        return True

    # -- publication ----------------------------------------------------------------------
    async def _counters(self) -> None:
        running = sum(op["state"] != "finished" for op in self.ops.values())
        await self.set("QueuedOperations", running)
        await self.set("CompletedOperations", len(self.ops) - running)

    async def _publisher(self) -> None:
        """Bring the units' possessions and the objects' PossessedBy in line with the
        ledger, retrying whatever could not be written (an asset that is away)."""
        units = set(self.node.floor.units)
        while True:
            for aid in sorted(self._pending):
                try:
                    if aid in units:
                        objs = [o for o in self.ledger.objects_at(aid)
                                if o not in self.state.data["unknown"]]  # fmt: skip
                        await asyncio.wait_for(self.node.peers.call(
                            aid, "SetPossessedObjects", ",".join(objs)), 5)  # fmt: skip
                    elif aid in self.ledger.locations():
                        lost = aid in self.state.data["unknown"]
                        where = "" if lost else self.ledger.location(aid)
                        await asyncio.wait_for(self.node.peers.write(aid, "PossessedBy", where), 5)
                    self._pending.discard(aid)
                except Exception as exc:
                    log.debug("TMS: %s not updated yet: %s", aid, exc)
            await asyncio.sleep(0.5)
