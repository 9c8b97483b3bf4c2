"""The TMS's order book (Open-RMF's dispatcher keeps one beside its auctioneer): every
operation with its state machine and history keyed by an id unique on the floor across
restarts, and the object ledger (where each object is, which operation holds it). What it
holds is the TMS's persisted state (`data`), saved on every change.

An order is checked against the ledger and its object reserved in one step (`accept`);
orders for one object chain (`chain`); a module's reports are applied exactly once
(`progress`); an operation ends with its result (`finish`), which also counts as evidence
of the state the object was loaded in (`record`). A failure in the middle of a transfer
leaves the object's place unknown until an operator says where it is (`locate`) or a late
report of the module settles it.
"""

from __future__ import annotations

import logging
import time
from collections.abc import Callable, Mapping
from typing import Any

from transfertwin.cps.apps import ObjectLedger
from transfertwin.cps.dispatch._kpis import kpis
from transfertwin.cps.dispatch._learn import record
from transfertwin.cps.floor import FloorSpec
from transfertwin.cps.opcua import OperationRefused

__all__ = ["OrderBook", "locate_advice", "order_view"]

log = logging.getLogger("transfertwin.cps")


class OrderBook:
    """The operations and the object ledger of a floor's TMS.

    Args:
        floor: The floor (its units, modules, objects, operation policy).
        data: The TMS's persisted state (`initial` the first time); changed in place.
        save: Writes `data` (atomically).
    """

    def __init__(self, floor: FloorSpec, data: dict[str, Any], save: Callable[[], None]) -> None:
        self.floor, self.data, self._save = floor, data, save
        modules = [m.asset_id for m in floor.modules]
        self.ledger = ObjectLedger(data["locations"], floor.units, modules)
        self.ops: dict[str, dict[str, Any]] = data["operations"]
        for op in self.ops.values():
            if op["state"] != "finished":
                self.ledger.hold(op["operation"], op["object"])
        self.pending: set[str] = set()  # holders/objects whose published location is stale

    @staticmethod
    def initial(floor: FloorSpec) -> dict[str, Any]:
        """The state of a TMS that has taken no order yet."""
        return {"next_op": 1, "locations": floor.placement(), "unknown": {},
                "operations": {}, "predictions": {}, "evidence": {}}  # fmt: skip

    def save(self) -> None:
        """Write the state with the ledger's locations."""
        self.data["locations"] = self.ledger.locations()
        self._save()

    def targets(self, destination: str) -> tuple[str, ...]:
        """The units a destination names: itself, or the units of its group."""
        if destination in self.floor.units:
            return (destination,)
        group = self.floor.operation.group(destination)
        if group is None:
            groups = [g for g, _ in self.floor.operation.groups]
            raise OperationRefused(
                f"no transfer unit or destination group {destination!r}; units: "
                f"{', '.join(self.floor.units)}"
                + (f"; groups: {', '.join(groups)}" if groups else ""), argument="target")
        return group

    def tail(self, obj: str) -> str | None:
        """The last unfinished operation of `obj` (the one a new order chains after)."""
        mine = [o for o in self.ops.values() if o["object"] == obj and o["state"] != "finished"]
        return max(mine, key=lambda o: int(o["operation"][2:]))["operation"] if mine else None

    def accept(self, obj: str, destination: str, source: str | None,
               modules: list[dict[str, Any]] | None) -> str:  # fmt: skip
        """Check an order, refuse what cannot start (`OperationRefused`, with the reason),
        else queue it: at once, or after the object's unfinished order (orders for one
        object chain). `modules`: the transport modules as the graph lists them (None: the
        graph is away, nothing is refused for their sake). Returns the operation id."""
        if obj not in self.ledger.locations():
            raise OperationRefused(f"{obj!r} is not an object of this floor; objects: "
                                   f"{', '.join(self.ledger.locations())}",
                                   argument="object")  # fmt: skip
        unknown = self.data["unknown"].get(obj)
        if unknown is not None:
            raise OperationRefused(
                f"where {obj} is is unknown since {unknown['operation']} "
                f"(last seen at {unknown['last_seen']}); say where it is with "
                f"'transfertwin cps locate'", status="BadInvalidState", argument="object")
        stuck = self.data.get("stuck", {}).get(obj)
        if stuck is not None and self.tail(obj) is None:
            raise OperationRefused(
                f"{obj} lies on {stuck['module']} outside a pre-transfer state (the scan of "
                f"{stuck['operation']}): no transfer can start from there and a module cannot "
                f"turn it; take it off, put it on a transfer unit and say where "
                f"('transfertwin cps locate --object {obj} --at UNIT')",
                status="BadInvalidState", argument="object")  # fmt: skip
        targets = self.targets(destination)
        after = self.tail(obj)
        if after is not None and source is not None:
            raise OperationRefused(f"{obj} is being moved by {after}; order it by destination "
                                   "to chain after it", status="BadInvalidState",
                                   argument="object")  # fmt: skip
        where = source or self.ledger.location(obj)
        online = [m for m in modules or () if m["online"]]
        if modules is not None and not online:
            raise OperationRefused("no transport module is online",
                                   status="BadResourceUnavailable")  # fmt: skip
        if after is None and where in self.floor.units and online and all(
                self.carried_by(m["id"]) for m in online):  # fmt: skip
            held = "; ".join(f"{m['id']} carries {', '.join(self.carried_by(m['id']))}"
                             for m in online)  # fmt: skip
            raise OperationRefused(f"every transport module carries an object ({held}): order "
                                   "those onward first", status="BadResourceUnavailable",
                                   argument="object")  # fmt: skip
        if after is None and where in targets:
            raise OperationRefused(f"{obj} is at {where} already, a unit of {destination}",
                                   argument="target")  # fmt: skip
        free = [t for t in targets if not self.occupied(t)]
        if not free:
            held = "; ".join(f"{t} holds {', '.join(self.ledger.objects_at(t))}" for t in targets)
            raise OperationRefused(f"the destination is occupied ({held}): order that away "
                                   "first", status="BadResourceUnavailable",
                                   argument="target")  # fmt: skip
        data = self.data
        op_id = f"op{data['next_op']}"
        if after is None:
            self.ledger.reserve(op_id, where, free[0], obj)
        data["next_op"] += 1
        single = len(targets) == 1
        self.ops[op_id] = {"operation": op_id, "object": obj,
                           "source": where if after is None else None,
                           "target": targets[0] if single else None,
                           "destination": destination, "targets": list(targets),
                           "after": after, "state": "queued", "phase": "queued",
                           "module": None, "submitted": time.time(), "steps": [],
                           "history": [[time.time(), "queued" if after is None else
                                        f"queued after {after}"]]}  # fmt: skip
        self.save()
        log.info("TMS: %s %s -> %s (%s) accepted%s", op_id, where, destination, obj,
                 f", after {after}" if after else "")  # fmt: skip
        return op_id

    def carried_by(self, module: str) -> list[str]:
        """The objects the ledger places on `module` (not those whose place is unknown).
        The ledger, not the module's last heartbeat, decides: a heartbeat may still list an
        object the module has just handed over."""
        return [o for o in self.ledger.objects_at(module) if o not in self.data["unknown"]]

    def occupied(self, unit: str) -> bool:
        """`unit` holds as many objects as the floor's capacity allows (0: no limit),
        counting none that an unfinished order takes away."""
        capacity = self.floor.operation.capacity
        if capacity == 0:
            return False
        leaving = {o["object"] for o in self.ops.values() if o["state"] != "finished"}
        return sum(o not in leaving for o in self.ledger.objects_at(unit)) >= capacity

    def locate(self, obj: str, holder: str) -> None:
        """An operator says where `obj` is (on a transfer unit); ValueError if it cannot be."""
        self.check_locate(obj, holder)
        self.move(obj, holder)
        log.info("TMS: an operator located %s at %s", obj, holder)

    def check_locate(self, obj: str, holder: str) -> None:
        """ValueError when `obj` cannot be located at `holder` (`locate`)."""
        if obj not in self.ledger.locations():
            raise ValueError(f"{obj!r} is not an object of this floor")
        if holder not in self.ledger.holders:
            raise ValueError(f"{holder!r} is no transfer unit or transport module of this floor")
        if holder not in self.floor.units:  # type E keeps its own state (Table 3.1)
            raise ValueError(f"{holder} is a transport module: it says itself what it carries; "
                             "put the object on a transfer unit and locate it there")
        if obj in self.ledger.moving():
            raise ValueError(f"{obj} is being moved by {self.ledger.moving()[obj]}")

    def move(self, obj: str, holder: str) -> None:
        """`obj` is on `holder` now (its place known again)."""
        previous = self.ledger.move(obj, holder)
        self.data["unknown"].pop(obj, None)
        self.data.get("stuck", {}).pop(obj, None)
        self.save()
        self.pending |= {previous, holder, obj}

    def chain(self, op_id: str) -> bool:
        """The order `op_id` chains after has ended: take the object from where it is now.
        False when the order ended here (the object lost, or already at the destination)."""
        op = self.ops[op_id]
        prev = op["after"]
        obj = op["object"]
        if obj in self.data["unknown"]:
            self.finish(op_id, {"status": "failed before start", "failed_step": "queued",
                                "reason": f"{obj} was lost by {prev}: its place is unknown",
                                "fault": True})  # fmt: skip
            return False
        where = self.ledger.location(obj)
        if where in op["targets"]:
            self.finish(op_id, {"status": "delivered", "reason": f"{obj} is at {where} "
                                f"already (after {prev})"})  # fmt: skip
            return False
        op["source"] = where
        self.ledger.hold(op_id, obj)
        op["history"].append([time.time(), f"{prev} ended: {obj} is at {where}"])
        self.save()
        return True

    def finish(self, op_id: str, result: dict[str, Any]) -> None:
        """End `op_id` with `result`: the ledger, the evidence of the object's states and
        the operation's record (an unknown place when the result says so)."""
        op = self.ops[op_id]
        obj = op["object"]
        if result.get("location_unknown"):
            self.data["unknown"][obj] = {"last_seen": self.ledger.location(obj),
                                         "operation": op_id}  # fmt: skip
            self.pending |= {self.ledger.location(obj), obj}
        self.ledger.release(op_id, obj)
        record(self.data.setdefault("evidence", {}), obj,
               (op.get("plan") or {}).get("state"), result)  # fmt: skip
        ok = result.get("status") == "delivered"
        where = self.ledger.location(obj)
        if not ok and where not in self.floor.units and where in self.ledger.holders and \
                result.get("failed_step") == "scanning" and \
                NOT_PRE_TRANSFER in str(result.get("reason", "")):  # fmt: skip
            # left on the module where no transfer can start: only an operator can help
            self.data.setdefault("stuck", {})[obj] = {"module": where, "operation": op_id}
        op.update(state="finished", phase="done" if ok else "failed", result=result,
                  location=self.where(obj), finished=time.time())  # fmt: skip
        if obj in self.data["unknown"]:  # the operator's next step, wherever the history shows
            op["history"].append([time.time(), locate_advice(obj)])
        op["history"].append([time.time(), op["phase"]])
        self.save()
        log.info("TMS: %s finished: %s; %s is at %s", op_id, result.get("status"), obj,
                 op["location"])  # fmt: skip

    def where(self, obj: str) -> str:
        """Where `obj` is, in words (its unit or module, or unknown since when)."""
        unknown = self.data["unknown"].get(obj)
        if unknown is None:
            return self.ledger.location(obj)
        return f"unknown, last seen at {unknown['last_seen']}"

    def progress(self, op_id: str, event: dict[str, Any]) -> bool:
        """Apply a module's report (saved before the TMS acknowledges it); True when it
        ended the operation."""
        op = self.ops.get(op_id)
        if op is None:
            raise ValueError(f"no operation {op_id!r}")
        kind = event.get("event")
        if kind == "moved":
            self.move(event["object"], event["holder"])
            op["history"].append([event.get("t", time.time()),
                                  f"{event['object']} onto {event['holder']}"])  # fmt: skip
        elif kind == "step" and op["state"] != "finished":
            op["phase"] = event["state"] if event["state"] != "idle" else op["phase"]
            unit = f" at {event['unit']}" if event.get("unit") else ""
            op["history"].append([event.get("t", time.time()), f"{event['state']}{unit}"])
            op.setdefault("steps", []).append(
                [event.get("t", time.time()), event["state"], event.get("unit")])
        elif kind == "result":
            if op["state"] == "finished":
                late = event["result"]
                op["history"].append([time.time(), f"late result: {late['status']}"])
                obj = op["object"]
                if (late.get("location_unknown") and obj not in self.ledger.moving()
                        and obj not in self.data["unknown"]):  # fmt: skip
                    # the module knows better than the lease did: the object may be in the gap
                    self.data["unknown"][obj] = {"last_seen": self.ledger.location(obj),
                                                 "operation": op_id}  # fmt: skip
                    self.pending |= {self.ledger.location(obj), obj}
                    op["history"].append([time.time(), locate_advice(obj)])
            else:
                self.finish(op_id, event["result"])
                return True
        self.save()
        return False

    def status(self, op_id: str) -> dict[str, Any]:
        """The whole record of `op_id` (OperationRefused when there is none)."""
        if op_id not in self.ops:
            raise OperationRefused(f"no operation {op_id!r}", argument="operation_id")
        return self.ops[op_id]

    def ledger_doc(self) -> dict[str, Any]:
        """Where every object is, which are unknown or moving, and every operation."""
        return {"locations": self.ledger.locations(), "unknown": self.data["unknown"],
                "moving": self.ledger.moving(), "operations": list(self.ops.values())}

    def kpi_doc(self, policy: str) -> dict[str, Any]:
        """The KPIs of the operations so far (`kpis`), with the policy."""
        doc = kpis(self.ops.values(), [m.asset_id for m in self.floor.modules],
                   self.floor.units, time.time())  # fmt: skip
        return {"policy": policy, **doc}

    def running(self) -> int:
        """Operations not finished yet."""
        return sum(op["state"] != "finished" for op in self.ops.values())


def locate_advice(obj: str) -> str:
    """What the operator does after an operation that left `obj` where the floor cannot say:
    the TMS refuses every order of it until someone says where it lies (`locate`)."""
    return (f"where {obj} lies is unknown to the floor; once you have found it, say so with "
            f"'transfertwin cps locate --object {obj} --at UNIT' (a transfer unit, or the "
            "transport module if it still carries it), then order it on")


#: Order states of `cps orders` by the operation's phase (the module's steps, Fig. 5.9a).
_ORDER_STATE = {"queued": "queued", "assigned": "assigned", "navigating": "driving",
                "docking": "docking", "scanning": "docking", "transferring": "transferring",
                "done": "done", "failed": "failed"}  # fmt: skip


#: What a module's scan says of an object that rests outside every pre-transfer state
#: (`cps.apps.form_ots`): on a module's belts it stays so until someone takes it off.
NOT_PRE_TRANSFER = "is not in a pre-transfer state"


def order_view(op: Mapping[str, Any]) -> dict[str, Any]:
    """One row of the order queue: id, object, from, to, state, module, reason."""
    result = op.get("result") or {}
    reason = result.get("reason") or None
    if op["phase"] == "queued" and op.get("after") and op["source"] is None:
        reason = f"waiting for {op['after']}"
    return {"operation": op["operation"], "object": op["object"], "source": op["source"],
            "destination": op.get("destination", op["target"]), "target": op["target"],
            "state": _ORDER_STATE.get(op["phase"], op["phase"]), "module": op.get("module"),
            "submitted": op["submitted"], "finished": op.get("finished"),
            "reason": reason, "location": op.get("location"),
            "loaded_state": (op.get("plan") or {}).get("state")}  # fmt: skip
