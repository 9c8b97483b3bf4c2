"""What the console knows of a floor, as pure functions over what it read (issue 27, item 8).

The console follows a floor as it changes: a CPS restarted in the same work folder writes a
new ``cps.json`` (new ports), an asset process that restarts keeps its endpoint but opens a
new session, an asset that joins at runtime (a standby transport module) is announced by
the knowledge graph's ``Status`` before anything else. The gateway (`CpsGateway`) does the
reading; this module decides what it means:

- `read_floor_info`: ``cps.json`` with a stamp that changes when the file is rewritten;
- `merge_assets`: the assets to watch, from ``cps.json`` and the graph's ``Status``;
- `asset_condition`: whether an asset is online and, if not, why (one reason, in words);
- `current_run_operations`: a single-process CPS's operations of *this* run from
  ``cps.log`` (the log grows across runs and operation ids restart at op1 there);
- `order_rows`: the Orders tab, one row per operation id, whoever placed it.
"""

from __future__ import annotations

import json
import re
from dataclasses import dataclass
from datetime import datetime
from pathlib import Path
from typing import Any

__all__ = [
    "FloorInfo",
    "asset_condition",
    "current_run_operations",
    "merge_assets",
    "order_rows",
    "read_floor_info",
]

_ACCEPTED = re.compile(r"TMS: (op\d+) (\w+) -> (\w+) \((\w+)\) accepted")
_TMS_LINE = re.compile(r"^TMS: (op\d+) (.*)$")
_STAMP = re.compile(r"^(\d{4}-\d\d-\d\d \d\d:\d\d:\d\d)(?:,\d+)? (.*)$")


@dataclass(frozen=True)
class FloorInfo:
    """The content of a ``cps.json`` and the stamp of the file it came from.

    Attributes:
        mode: "processes" (one process per asset, ``cps up --floor``) or "single".
        assets: One dict per asset: id, kind, class, endpoint, security_policy (and type).
        credentials_file: The OPC UA user credentials (None when insecure).
        cert_dir: Where the console's client certificates are.
        insecure: NoSecurity (``--insecure``).
        stamp: (mtime ns, size, inode) of cps.json: changes when a CPS rewrites it.
        started: When cps.json was written (local time, as cps.log's timestamps are).
        groups: Destination groups of a process floor (name, units), orderable by name.
    """

    mode: str
    assets: tuple[dict[str, Any], ...]
    credentials_file: Path | None
    cert_dir: Path
    insecure: bool
    stamp: tuple[int, int, int]
    started: datetime
    groups: tuple[tuple[str, tuple[str, ...]], ...] = ()


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
        mode=str(info.get("mode", "single")),
        assets=tuple(info.get("assets", ())),
        credentials_file=Path(creds) if creds else None,
        cert_dir=Path(info["cert_dir"]),
        insecure=bool(info.get("insecure")),
        stamp=(st.st_mtime_ns, st.st_size, st.st_ino),
        started=datetime.fromtimestamp(st.st_mtime).replace(microsecond=0),
        groups=tuple((str(g), tuple(u)) for g, u in info.get("groups", ())),
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
            the graph has no ``Status`` (single-process CPS) or is not answering.

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
        return False, f"not answering ({session_error})"
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


def _stamped(line: str) -> tuple[datetime | None, str]:
    m = _STAMP.match(line)
    if m is None:
        return None, line
    return datetime.strptime(m.group(1), "%Y-%m-%d %H:%M:%S"), m.group(2)


def current_run_operations(lines: list[str], started: datetime) -> dict[str, dict[str, Any]]:
    """A single-process CPS's operations of its current run, from its log (pure).

    cps.log keeps every run of a work folder and that CPS numbers its operations from op1
    on every start: only the lines after the last ``CPS up`` belong to this run (without
    one, the lines stamped at or after `started`, when cps.json was written). A module's
    own lines (``TM_1: docked at TU_C ...``) go to the operation allocated to it.

    Returns:
        Operation id -> {operation, object, source, target, state, outcome, history}
        with history a list of log texts (without their time stamps), in log order.
    """
    marks = [i for i, ln in enumerate(lines) if _stamped(ln)[1].startswith("CPS up")]
    first = marks[-1] + 1 if marks else 0
    ops: dict[str, dict[str, Any]] = {}
    module_op: dict[str, str] = {}
    for line in lines[first:]:
        t, text = _stamped(line)
        if t is None or (not marks and t < started):
            continue
        m = _ACCEPTED.search(text)
        if m is not None:
            op, source, target, obj = m.groups()
            ops[op] = {"operation": op, "object": obj, "source": source, "target": target,
                       "state": "queued", "outcome": None, "history": []}  # fmt: skip
        m = _TMS_LINE.match(text)
        if m is None:
            who = text.split(":", 1)[0]
            if who in module_op and ":" in text:
                ops[module_op[who]]["history"].append(text)
            continue
        op, rest = m.groups()
        rec = ops.get(op)
        if rec is None:
            continue
        rec["history"].append(text)
        if rest.startswith("finished: "):
            rec["state"], rec["outcome"] = "finished", rest[len("finished: "):].strip()
            module_op = {k: v for k, v in module_op.items() if v != op}
        elif rest.startswith("allocated to "):
            rec["state"] = "running"
            module_op[rest[len("allocated to "):].strip()] = op
    return ops


def _ledger_row(op: dict[str, Any]) -> dict[str, Any]:
    """A TMS ledger operation as an Orders-tab row (history as timestamped steps)."""
    result = op.get("result") or {}
    outcome = result.get("status")
    if outcome and result.get("reason"):
        outcome += f" ({result.get('failed_step') or 'step'}: {result['reason']})"
    steps = [{"t": float(t), "text": str(what)} for t, what in op.get("history", ())]
    return {"id": op["operation"], "operation": op["operation"], "object": op.get("object"),
            "source": op.get("source"), "target": op.get("target"),
            "state": op.get("state", "queued"), "outcome": outcome,
            "module": op.get("module"), "steps": steps, "placed_by": "cps",
            "submitted": op.get("submitted")}  # fmt: skip


def order_rows(
    operations: list[dict[str, Any]],
    placed: list[dict[str, Any]],
    *,
    from_ledger: bool,
) -> list[dict[str, Any]]:
    """The Orders tab: one row per operation id, whoever placed it (console or CLI), oldest
    first; an order placed here keeps its console id and adds the TMS's history.

    Args:
        operations: The TMS's ``Ledger()`` operations (``from_ledger``), or the current
            run's operations from `current_run_operations` (history of log texts).
        placed: The console's own orders (`Order.public()`), each with its operation id.
        from_ledger: Which of the two `operations` are.
    """
    rows: dict[str, dict[str, Any]] = {}
    for op in operations:
        if from_ledger:
            rows[op["operation"]] = _ledger_row(op)
        else:
            rows[op["operation"]] = {
                "id": op["operation"], "operation": op["operation"], "object": op["object"],
                "source": op["source"], "target": op["target"], "state": op["state"],
                "outcome": op["outcome"], "module": None, "placed_by": "cps",
                "steps": [{"t": None, "text": h} for h in op["history"]]}  # fmt: skip
    out: list[dict[str, Any]] = []
    for order in placed:
        row = rows.pop(order.get("operation") or "", None)
        merged = dict(order, placed_by="console")
        if row is not None and from_ledger:  # the TMS's record is the authority
            merged.update(state=row["state"], outcome=row["outcome"], steps=row["steps"],
                          module=row["module"])  # fmt: skip
        out.append(merged)
    out.extend(rows.values())
    return sorted(out, key=lambda r: _op_number(r.get("operation")))


def _op_number(op: object) -> int:
    m = re.fullmatch(r"op(\d+)", str(op or ""))
    return int(m.group(1)) if m else 1 << 62
