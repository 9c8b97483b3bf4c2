"""The console's order desk: transport orders placed through the console, checked against
the floor and followed to their end (`OrderDesk`, mixed into `CpsGateway`).

Every operation has one id, given by the TMS; the Orders tab lists the floor's operations
by that id from the TMS's ``Ledger()`` (ids unique across restarts of the floor), whoever
placed them (`transfertwin.web._floor.order_rows`). The console's own orders are kept in
``W/console-orders.json``, so an order placed here is still shown as the console's after
the floor or the console restarted.
"""

from __future__ import annotations

import contextlib
import json
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


@dataclass
class Order:
    """A transport order placed through the console (its state and history are the TMS's
    once the TMS took it: `order_rows`)."""

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

    def step(self, text: str) -> None:
        """Append a timestamped step (once per distinct text in a row)."""
        if not self.steps or self.steps[-1]["text"] != text:
            self.steps.append({"t": time.time(), "text": text})

    def record(self) -> dict[str, object]:
        """What the console keeps of it across restarts (`Order.from_record`)."""
        return {"id": self.id, "object": self.object, "source": self.source,
                "target": self.target, "submitted_utc": self.submitted_utc,
                "client": self.client, "operation": self.operation}  # fmt: skip

    @classmethod
    def from_record(cls, rec: dict[str, Any]) -> Order:
        return cls(str(rec["id"]), str(rec["object"]), str(rec["source"]), str(rec["target"]),
                   str(rec["submitted_utc"]), str(rec["client"]),
                   operation=rec.get("operation"), state="running")  # fmt: skip

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
        """Destination groups an order may name as its target."""
        return []

    def _unit(self, what: str, value: object) -> str:
        """A transfer unit id, or the unit standing at a station named by its id (or, for
        the target, a destination group)."""
        units = self.ids_of("transfer_unit")
        if value is None or value == "":
            raise InputError(f"the order has no {what}: choose a transfer unit or station "
                             f"({', '.join(units)})")  # fmt: skip
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
        if obj is None or obj == "":
            raise InputError(f"the order has no object: choose one of {', '.join(objects)}")
        if not isinstance(obj, str) or obj not in objects:
            raise InputError(f"object must be one of {', '.join(objects)}, got {obj!r:.70}")
        target = self._unit("target", body.get("target"))
        source = body.get("source") or None
        if source is None:
            return obj, None, target  # the TMS finds where it is (OrderTo): orders chain
        if source not in self._module_sources():
            source = self._unit("source", source)
        if source == target:
            raise InputError(f"source and target are both {source}: nothing to transport")
        return obj, source, target

    def _module_sources(self) -> list[str]:
        """Transport modules an order may start from (an object left on a module)."""
        return []

    async def submit(self, obj: str, source: str | None, target: str, client: str) -> Order:
        """Place a validated order with the TMS (by destination when `source` is None); the
        TMS's ledger carries its history and outcome from then on."""
        order = Order(f"w{self._next_order()}", obj, source or "where it is", target,
                      datetime.now(UTC).isoformat(timespec="seconds"), client)  # fmt: skip
        try:
            if source is None:
                order.operation = str(await self._tms_call("OrderTo", obj, target))
                status = json.loads(await self._tms_call("OperationStatus", order.operation))
                order.source = status.get("source") or f"where {obj} is after {status['after']}"
            else:
                order.operation = str(await self._tms_call("SubmitTransportOperation", source,
                                                           target, obj))  # fmt: skip
        except ua.UaStatusCodeError as exc:
            reason = status_text(exc)
            audit.info("order refused: %s %s -> %s from %s: %s", obj, source or "where it is",
                       target, client, reason)  # fmt: skip
            raise InputError(f"the TMS refused the order: {reason}") from None
        self.orders[order.id] = order
        self._keep_orders()
        order.state = "running"
        order.step(f"submitted to the TMS as {order.operation}: {obj} {order.source} -> "
                   f"{target}")  # fmt: skip
        audit.info("order %s (%s): %s %s -> %s from %s", order.id, order.operation, obj,
                   order.source, target, client)  # fmt: skip
        return order

    def _next_order(self) -> int:
        """The number of the next console id (``w<N>``), after every kept one."""
        numbers = [int(i[1:]) for i in self.orders if i[1:].isdigit()]
        return max(numbers, default=0) + 1

    def _keep_orders(self) -> None:
        """Keep the console's orders (atomically) for the next console or floor start."""
        raise NotImplementedError

    async def _tms_call(self, operation: str, *args: object) -> Any:
        raise NotImplementedError
