"""The console's order desk: transport orders placed through the console, checked against
the floor and followed to their end (`OrderDesk`, mixed into `CpsGateway`).

Every operation has one id, given by the TMS; the Orders tab lists the floor's operations
by that id, whoever placed them (`transfertwin.web._floor.order_rows`): on a process floor
from the TMS's ``Ledger()`` (ids unique across restarts), on a single-process CPS from the
current run's lines of ``cps.log`` (that CPS numbers from op1 on every start).
"""

from __future__ import annotations

import asyncio
import contextlib
import logging
import re
import time
from dataclasses import dataclass, field
from datetime import UTC, datetime
from typing import Any

from asyncua import ua

from transfertwin._errors import InputError

__all__ = ["Order", "OrderDesk"]

audit = logging.getLogger("transfertwin.web.audit")

_ID = re.compile(r"^[A-Za-z0-9_]{1,64}$")
LOCATION_QUERY = """
PREFIX tt: <https://transfertwin.dev/ontology#>
SELECT ?holder WHERE {
  { ?h tt:possesses ?o . } UNION { ?o tt:locatedAt ?h . }
  ?o tt:assetId "%s" . ?h tt:assetId ?holder .
}
"""


@dataclass
class Order:
    """A transport order placed through the console.

    Attributes:
        run: The stamp of the cps.json it was placed under: a single-process CPS started
            again in the same folder numbers its operations from op1 again, so an order
            of an earlier run is never matched with this run's operation of the same id.
    """

    id: str
    object: str
    source: str
    target: str
    submitted_utc: str
    client: str
    operation: str | None = None
    state: str = "submitted"  # submitted | running | finished | refused | lost
    outcome: str | None = None
    steps: list[dict[str, Any]] = field(default_factory=list)
    run: tuple[int, int, int] | None = None

    def step(self, text: str) -> None:
        """Append a timestamped step (once per distinct text in a row)."""
        if not self.steps or self.steps[-1]["text"] != text:
            self.steps.append({"t": time.time(), "text": text})

    def public(self) -> dict[str, object]:
        """The order as the browser sees it."""
        return {"id": self.id, "object": self.object, "source": self.source,
                "target": self.target, "submitted_utc": self.submitted_utc,
                "operation": self.operation, "state": self.state, "outcome": self.outcome,
                "steps": list(self.steps)}  # fmt: skip


def status_text(exc: ua.UaStatusCodeError) -> str:
    """The reason of a refused call, or the status code's name."""
    reason = getattr(exc, "reason", None)
    if reason:
        return str(reason)
    with contextlib.suppress(Exception):
        return ua.StatusCode(exc.code).name
    return str(exc)


class OrderDesk:
    """Placing and following orders; the gateway provides the sessions and the floor."""

    orders: dict[str, Order]
    kg_rows: list[dict[str, Any]]
    period_s: float

    def ids_of(self, cls: str) -> list[str]:  # provided by the gateway
        raise NotImplementedError

    def destination_groups(self) -> list[str]:
        """Destination groups an order may name as its target (a process floor's)."""
        return []

    def _unit(self, what: str, value: object) -> str:
        """A transfer unit id, or the unit standing at a station named by its id (or, for
        the target, a destination group)."""
        units = self.ids_of("transfer_unit")
        if not isinstance(value, str) or not _ID.match(value):
            raise InputError(f"{what} must be a transfer unit or station id, got {value!r:.70}")
        if value in units or (what == "target" and value in self.destination_groups()):
            return value
        at = [r["id"] for r in self.kg_rows if r.get("station") == value and r["id"] in units]
        if len(at) == 1:
            return at[0]
        raise InputError(f"{what} {value}: no such transfer unit or station; units: "
                         f"{', '.join(units)}")  # fmt: skip

    async def validate_order(self, body: dict[str, Any]) -> tuple[str, str, str]:
        """(object, source unit, target unit) of an order, or InputError with the reason."""
        unknown = sorted(set(body) - {"object", "source", "target", "token"})
        if unknown:
            raise InputError(f"unknown field(s): {', '.join(unknown)}")
        obj = body.get("object")
        objects = self.ids_of("object")
        if not isinstance(obj, str) or obj not in objects:
            raise InputError(f"object must be one of {', '.join(objects)}, got {obj!r:.70}")
        target = self._unit("target", body.get("target"))
        source = body.get("source") or None
        if source is None and self.by_destination():
            return obj, None, target  # the TMS finds where it is (OrderTo): orders chain
        if source is None:
            source = await self._where(obj)
        if source not in self._module_sources():
            source = self._unit("source", source)
        if source == target:
            raise InputError(f"source and target are both {source}: nothing to transport")
        return obj, source, target

    async def _where(self, obj: str) -> str:
        """Where an object lies (the TMS's ledger, else the graph)."""
        raise NotImplementedError

    def _module_sources(self) -> list[str]:
        """Transport modules an order may start from (an object left on a module)."""
        return []

    def by_destination(self) -> bool:
        """The TMS takes orders by destination (`OrderTo`; a process floor's)."""
        return False

    async def submit(self, obj: str, source: str | None, target: str, client: str) -> Order:
        """Place a validated order with the TMS (by destination when `source` is None); it
        is followed in the background."""
        order = Order(f"w{len(self.orders) + 1}", obj, source or "where it is", target,
                      datetime.now(UTC).isoformat(timespec="seconds"), client,
                      run=self._run_stamp())  # fmt: skip
        try:
            if source is None:
                order.operation = str(await self._tms_call("OrderTo", obj, target))
            else:
                order.operation = str(await self._tms_call("SubmitTransportOperation", source,
                                                           target, obj))  # fmt: skip
        except ua.UaStatusCodeError as exc:
            reason = status_text(exc)
            audit.info("order refused: %s %s -> %s from %s: %s", obj, source, target, client,
                       reason)  # fmt: skip
            raise InputError(f"the TMS refused the order: {reason}") from None
        self.orders[order.id] = order
        order.state = "running"
        order.step(f"submitted to the TMS as {order.operation}: {obj} {source} -> {target}")
        audit.info("order %s (%s): %s %s -> %s from %s", order.id, order.operation, obj,
                   source, target, client)  # fmt: skip
        self._follow_later(order)
        return order

    def _run_stamp(self) -> tuple[int, int, int] | None:
        raise NotImplementedError

    async def _tms_call(self, operation: str, *args: object) -> Any:
        raise NotImplementedError

    def _follow_later(self, order: Order) -> None:
        raise NotImplementedError

    async def _follow(self, order: Order, timeout_s: float = 1800.0) -> None:
        """Follow a single-process CPS's operation: the modules' state while the log has
        nothing yet, the current run's log lines, and the TMS's OperationStatus."""
        import json

        tms_ids = self.ids_of("transport_module")
        op = str(order.operation)
        deadline = time.monotonic() + timeout_s
        shown = 0
        while time.monotonic() < deadline:
            if order.run != self._run_stamp():  # the CPS was started again meanwhile
                order.state = "lost"
                order.step("the CPS restarted before the operation ended")
                return
            record = self._run_operations().get(op)
            lines = record["history"] if record else []
            for tm in tms_ids if not lines else ():
                v = self.values.get(tm, {})
                if v.get("State") not in (None, "", "idle") or v.get("DockedAt"):
                    docked = f", docked at {v['DockedAt']}" if v.get("DockedAt") else ""
                    task = f" ({v['CurrentTask']})" if v.get("CurrentTask") else ""
                    order.step(f"{tm}: {v.get('State')}{docked}{task}")
            for ln in lines[shown:]:
                order.step(ln)
            shown = len(lines)
            status = None
            with contextlib.suppress(ua.UaStatusCodeError, OSError, TimeoutError):
                status = json.loads(await self._tms_call("OperationStatus", op))
            if status is not None and status.get("state") == "finished":
                order.outcome = str((status.get("result") or {}).get("status", "finished"))
            elif record is not None and record["outcome"] is not None:
                order.outcome = record["outcome"]
            if order.outcome is not None:
                order.state = "finished"
                order.step(f"finished: {order.outcome}")
                audit.info("order %s (%s) finished: %s", order.id, op, order.outcome)
                return
            await asyncio.sleep(self.period_s)
        order.state = "lost"
        order.step(f"no outcome within {timeout_s:g} s")

    values: dict[str, dict[str, Any]]

    def _run_operations(self) -> dict[str, dict[str, Any]]:
        raise NotImplementedError
