"""What the console knows of a floor, as pure functions over what it read.

The console follows a floor as it changes: a floor restarted in the same work folder writes a
new ``cps.json`` (new ports), an asset process that restarts keeps its endpoint but opens a
new session, an asset that joins at runtime (a standby transport module) is announced by
the knowledge graph's ``Status`` before anything else. The gateway (`CpsGateway`) does the
reading; this module decides what it means:

- `read_floor_info`: ``cps.json`` with a stamp that changes when the file is rewritten;
- `merge_assets`: the assets to watch, from ``cps.json`` and the graph's ``Status``;
- `asset_condition`: whether an asset is online and, if not, why (one reason, in words);
- `order_rows`: the Orders tab, one row per operation of the TMS's ledger (its ids are
  unique across restarts), with who placed it.
"""

from __future__ import annotations

import json
import re
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from transfertwin.web._display import step_text, unreachable_text

__all__ = [
    "FloorInfo",
    "asset_condition",
    "merge_assets",
    "order_rows",
    "read_floor_info",
]


@dataclass(frozen=True)
class FloorInfo:
    """The content of a ``cps.json`` and the stamp of the file it came from.

    Attributes:
        assets: One dict per asset: id, kind, class, endpoint, security_policy (and type).
        credentials_file: The OPC UA user credentials (None when insecure).
        cert_dir: Where the console's client certificates are.
        insecure: NoSecurity (``--insecure``).
        stamp: (mtime ns, size, inode) of cps.json: changes when a CPS rewrites it.
        groups: Destination groups of the floor (name, units), orderable by name.
        reader_role: The role the console reads the assets with: ``viewer``, or
            ``operator`` where it holds an operator credential only (``web --graph``).
    """

    assets: tuple[dict[str, Any], ...]
    credentials_file: Path | None
    cert_dir: Path
    insecure: bool
    stamp: tuple[int, int, int]
    groups: tuple[tuple[str, tuple[str, ...]], ...] = ()
    reader_role: str = "viewer"


def read_floor_info(workdir: Path) -> FloorInfo | None:
    """``W/cps.json`` as a `FloorInfo`; None when there is none (the CPS is stopped) or it is
    being rewritten (not JSON yet)."""
    path = workdir / "cps.json"
    try:
        st = path.stat()
        info = json.loads(path.read_text())
    except (OSError, ValueError):
        return None
    creds = info.get("credentials_file")
    return FloorInfo(
        assets=tuple(info.get("assets", ())),
        credentials_file=Path(creds) if creds else None,
        cert_dir=Path(info["cert_dir"]),
        insecure=bool(info.get("insecure")),
        stamp=(st.st_mtime_ns, st.st_size, st.st_ino),
        groups=tuple((str(g), tuple(u)) for g, u in info.get("groups") or ()),
        reader_role=str(info.get("reader_role", "viewer")),
    )


def merge_assets(
    info_assets: tuple[dict[str, Any], ...] | list[dict[str, Any]],
    status: list[dict[str, Any]] | None,
) -> dict[str, dict[str, Any]]:
    """The assets to watch: every asset of ``cps.json``, and every asset the knowledge
    graph's ``Status`` lists that ``cps.json`` does not (one that joined at runtime, with
    the address it announced).

    Args:
        info_assets: ``cps.json``'s assets.
        status: ``Status()``'s ``assets`` (id, kind, class, address, ...), or None where
            the graph is not answering.

    Returns:
        Asset id -> {id, kind, class, type, endpoint, security_policy}, sorted by id.
    """
    out = {a["id"]: dict(a) for a in info_assets}
    policy = next((a.get("security_policy") for a in info_assets), None)
    for row in status or ():
        aid = row.get("id")
        if not isinstance(aid, str) or aid in out or not row.get("address"):
            continue
        out[aid] = {"id": aid, "kind": row.get("kind"), "class": row.get("class"),
                    "role_class": row.get("role_class", row.get("class")),
                    "type": None, "endpoint": row["address"], "security_policy": policy,
                    "joined": True}  # fmt: skip
    return dict(sorted(out.items()))


def asset_condition(
    session_up: bool,
    session_error: str | None,
    kg_row: dict[str, Any] | None,
    floor_error: str | None = None,
    standby: bool = False,
) -> tuple[bool, str | None]:
    """Whether an asset is online, and why not (pure).

    On a process floor the graph's lease decides: an asset whose heartbeats arrive is
    online even while the console's own session to it is still being (re)opened; one the
    graph lists offline says whether it left (announced) or its lease lapsed, and since
    when; one prepared on standby and never started says so.

    Args:
        session_up: The console's viewer session reads the asset's values now.
        session_error: Why the last session attempt failed (e.g. 'ConnectionRefusedError').
        kg_row: The asset's row of the graph's ``Status`` (process floors), or None.
        floor_error: Why the floor itself is not there (no cps.json), or None.
        standby: cps.json marks the asset as prepared on standby (not started).

    Returns:
        (online, reason): the reason is None when online, else one line in words.
    """
    if floor_error is not None:
        return False, floor_error
    if session_up:
        return True, None
    if kg_row is not None and kg_row.get("online"):
        return True, None  # up (its lease is held); the console's session follows
    if kg_row is not None:
        return False, _offline_reason(kg_row)
    if standby:
        return False, "on standby (prepared, not started)"
    if session_error:
        return False, unreachable_text(session_error)
    return False, "connecting"


def _offline_reason(kg_row: dict[str, Any]) -> str:
    """An offline asset's reason from the graph's row: left or lapsed, and since when."""
    off = kg_row.get("offline") or {}
    ago = off.get("since_s")
    when = f" {ago:.0f} s ago" if isinstance(ago, int | float) else ""
    if off.get("reason") == "left":
        return f"left the floor{when} (announced)"
    if off.get("reason") == "lapsed":
        return f"lease lapsed{when} ({off.get('detail') or 'no heartbeat'})"
    seen = kg_row.get("last_seen_s")
    ago = f"last heartbeat {seen:.0f} s ago" if isinstance(seen, int | float) else "no lease"
    return f"left the floor ({ago})"


def _ledger_row(op: dict[str, Any]) -> dict[str, Any]:
    """A TMS ledger operation as an Orders-tab row (history as timestamped steps)."""
    result = op.get("result") or {}
    outcome = result.get("status")
    if outcome and result.get("reason"):
        outcome += f" ({result.get('failed_step') or 'step'}: {result['reason']})"
    steps = [{"t": float(t), "text": step_text(str(what))} for t, what in op.get("history", ())]
    return {"id": op["operation"], "operation": op["operation"], "object": op.get("object"),
            "source": op.get("source"), "target": op.get("target"),
            "state": op.get("state", "queued"), "outcome": outcome,
            "module": op.get("module"), "steps": steps, "placed_by": "cps",
            "submitted": op.get("submitted")}  # fmt: skip


def order_rows(operations: list[dict[str, Any]],
               placed: list[dict[str, Any]]) -> list[dict[str, Any]]:  # fmt: skip
    """The Orders tab: one row per operation of the TMS's ledger, oldest first, with who
    placed it: an order placed through the console keeps its console id and client, and
    the TMS's record (state, outcome, history) is the authority; every other one came from
    the command line or another client.

    Args:
        operations: The TMS's ``Ledger()`` operations.
        placed: The console's own orders (`Order.public()`), each with its operation id.
    """
    rows = {op["operation"]: _ledger_row(op) for op in operations}
    out: list[dict[str, Any]] = []
    for order in placed:
        row = rows.pop(order.get("operation") or "", None)
        merged = dict(order, placed_by="console")
        if row is not None:  # the TMS's record is the authority
            merged.update(
                state=row["state"],
                outcome=row["outcome"],
                steps=row["steps"],
                module=row["module"],
                source=row["source"] or order["source"],
            )
        out.append(merged)
    out.extend(rows.values())
    return sorted(out, key=lambda r: _op_number(r.get("operation")))


def _op_number(op: object) -> int:
    m = re.fullmatch(r"op(\d+)", str(op or ""))
    return int(m.group(1)) if m else 1 << 62
