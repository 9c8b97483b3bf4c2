"""What an object's AAS shows of its transfers (Sec. 5.1.3: a type B asset, kept by others).

The Transport Module System owns the operations, so it keeps the object's OperationalData
current: beside ``PossessedBy`` (where it lies) the pre-transfer state of its latest
transfer (``Face``, ``Conveyor``, ``Theta``: Eq. 5.5, 5.6, 5.4), the outcome of its last
finished transfer (``LastTransfer``) and its transfer history (``TransferHistoryJson``).
`object_properties` computes those values from the TMS's operation records (pure).
"""

from __future__ import annotations

import json
import math
from collections.abc import Iterable, Mapping
from typing import Any

__all__ = ["HISTORY_LIMIT", "object_properties"]

#: The most recent finished transfers an object's ``TransferHistoryJson`` lists.
HISTORY_LIMIT = 50


def _state(op: Mapping[str, Any]) -> Mapping[str, Any] | None:
    """The state the object was (or is being) loaded in: the module's final one (a retried
    pick-up may change it), else the plan's."""
    return (op.get("result") or {}).get("loaded_state") or (op.get("plan") or {}).get("state")


def _transferring(op: Mapping[str, Any]) -> bool:
    """Whether a running operation has begun to transfer its object (its state holds)."""
    return any(step[1] == "transferring" for step in op.get("steps") or ())


def _entry(op: Mapping[str, Any]) -> dict[str, Any]:
    state = _state(op) or {}
    return {
        "operation": op["operation"],
        "source": op.get("source"),
        "target": op.get("target"),
        "module": op.get("module"),
        "outcome": (op.get("result") or {}).get("status", ""),
        "face": state.get("face"),
        "conveyor": state.get("conveyor"),
        "theta_deg": state.get("theta_deg"),
        "submitted": op.get("submitted"),
        "finished": op.get("finished"),
    }


def object_properties(obj: str, operations: Iterable[Mapping[str, Any]]) -> dict[str, Any]:
    """The object's OperationalData values beyond ``PossessedBy``.

    Args:
        obj: The object's id.
        operations: The TMS's operation records (``operation``, ``object``, ``state``,
            ``submitted``, ``plan.state``, ``result.status``, ``result.loaded_state``, …),
            in any order.

    Returns:
        ``Face``, ``Conveyor`` ('' before any transfer), ``Theta`` (rad): the state of the
        latest transfer that began (a running operation's once it transfers), ``LastTransfer``
        (the last finished transfer's outcome, e.g. 'delivered', 'failed at pick-up'; ''
        before any) and ``TransferHistoryJson`` (its finished transfers, oldest first, at
        most `HISTORY_LIMIT`).
    """
    mine = sorted(
        (op for op in operations if op.get("object") == obj),
        key=lambda op: (op.get("submitted") or 0.0, op["operation"]),
    )
    finished = [op for op in mine if op.get("state") == "finished"]
    loaded = [op for op in mine if op.get("state") == "finished" or _transferring(op)]
    states = [s for s in map(_state, loaded) if s]
    latest = states[-1] if states else {}
    return {
        "Face": latest.get("face", ""),
        "Conveyor": latest.get("conveyor", ""),
        "Theta": math.radians(latest.get("theta_deg", 0)),
        "LastTransfer": (finished[-1].get("result") or {}).get("status", "") if finished else "",
        "TransferHistoryJson": json.dumps([_entry(op) for op in finished[-HISTORY_LIMIT:]]),
    }
