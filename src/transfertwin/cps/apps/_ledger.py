"""Where every object of the CPS is, and which transport operation holds it (TMS state).

The Transport Module System owns this ledger. An order is checked against it and, if it
is possible, reserves its object in the same step (no await in between on the event
loop, and a lock for threads), so two orders for one object cannot both be accepted: the
second is refused because the object is being moved, or, once the first has finished,
because the object is no longer at the source. The transport module reports each
completed transfer (`move`); the reservation ends when the operation ends (`release`).

Refusals are `OperationRefused` with the OPC UA status the TMS answers with:
BadInvalidArgument for names that do not exist or a source that equals the target,
BadInvalidState for an order that conflicts with where the object is.
"""

from __future__ import annotations

import threading
from collections.abc import Iterable, Mapping

from transfertwin._errors import InputError
from transfertwin.cps.opcua import OperationRefused

__all__ = ["ObjectLedger"]


class ObjectLedger:
    """Locations of the objects and the reservations of running operations.

    Args:
        locations: Object id -> id of the asset it lies on (initial placement).
        units: Ids of the transfer units orders may name as source or target.
        carriers: Ids of other assets an object may lie on (transport modules).
    """

    def __init__(
        self, locations: Mapping[str, str], units: Iterable[str], carriers: Iterable[str] = ()
    ) -> None:
        self._at = dict(locations)
        self._units = tuple(sorted(units))
        self.holders = frozenset(self._units) | frozenset(carriers)
        self._moving: dict[str, str] = {}  # object -> operation id
        self._lock = threading.Lock()
        for obj, holder in self._at.items():
            if holder not in self.holders:
                raise InputError(f"{obj}: initial location {holder!r} is not a transfer unit")

    def location(self, obj: str) -> str:
        """Id of the asset `obj` lies on."""
        with self._lock:
            return self._at[obj]

    def locations(self) -> dict[str, str]:
        """Object id -> asset id, sorted by object."""
        with self._lock:
            return dict(sorted(self._at.items()))

    def objects_at(self, holder: str) -> list[str]:
        """Objects lying on `holder`, sorted."""
        with self._lock:
            return sorted(o for o, h in self._at.items() if h == holder)

    def moving(self) -> dict[str, str]:
        """Object id -> id of the operation that holds it."""
        with self._lock:
            return dict(self._moving)

    def check(self, source: str, target: str, obj: str) -> None:
        """Refuse an order that names no transfer unit, no object of the CPS, the same unit
        twice, an object that is being moved, or an object that is not at the source.

        Raises:
            OperationRefused: With the reason and the offending argument.
        """
        with self._lock:
            self._check(source, target, obj)

    def reserve(self, op_id: str, source: str, target: str, obj: str) -> None:
        """`check` the order and reserve its object for `op_id` (atomically)."""
        with self._lock:
            self._check(source, target, obj)
            self._moving[obj] = op_id

    def hold(self, op_id: str, obj: str) -> None:
        """Reserve `obj` for `op_id` without a check (an operation resumed after a restart)."""
        with self._lock:
            self._moving[obj] = op_id

    def move(self, obj: str, holder: str) -> str:
        """Record that a transfer put `obj` onto `holder`; returns the previous holder."""
        with self._lock:
            previous = self._at[obj]
            self._at[obj] = holder
            return previous

    def release(self, op_id: str, obj: str) -> None:
        """End the reservation of `obj` by `op_id` (no-op if it does not hold it)."""
        with self._lock:
            if self._moving.get(obj) == op_id:
                del self._moving[obj]

    def _check(self, source: str, target: str, obj: str) -> None:
        if source not in self.holders:  # an object on a carrier can be ordered onward
            raise OperationRefused(
                f"no transfer unit {source!r}; units: {', '.join(self._units)}", argument="source"
            )
        if target not in self._units:
            raise OperationRefused(
                f"no transfer unit {target!r}; units: {', '.join(self._units)}", argument="target"
            )
        if source == target:
            raise OperationRefused(f"source and target are both {source}", argument="target")
        if obj not in self._at:
            raise OperationRefused(
                f"{obj!r} is not an object of this CPS; objects: {', '.join(sorted(self._at))}",
                argument="object",
            )
        if obj in self._moving:
            raise OperationRefused(
                f"{obj} is being moved by {self._moving[obj]}",
                status="BadInvalidState",
                argument="object",
            )
        if self._at[obj] != source:
            raise OperationRefused(
                f"{obj} is at {self._at[obj]}, not at {source}",
                status="BadInvalidState",
                argument="source",
            )
