"""The console's side of the CPS: the knowledge graph's view of the assets, live values
read over OPC UA, AAS browsing and transport orders.

The gateway reads ``cps.json`` and the credentials file of a running `transfertwin cps up`
and talks to the assets through the CPS client API (`transfertwin.cps.opcua.connect`): an
*viewer* session per asset for the live values and browsing, *operator* sessions for the
knowledge-graph queries and the orders (the only calls). Credentials stay in this process;
nothing returned to the browser carries them.
"""

from __future__ import annotations

import asyncio
import contextlib
import itertools
import json
import logging
import re
import time
from dataclasses import dataclass, field
from datetime import UTC, datetime
from pathlib import Path
from typing import Any

from asyncua import ua

from transfertwin._errors import InputError
from transfertwin.cps.opcua import (
    NAMESPACE,
    AssetClient,
    Credentials,
    connect,
    ensure_certificate,
    node_id,
)
from transfertwin.cps.opcua import load_credentials as _load_credentials

__all__ = ["ASSETS_QUERY", "CAPABILITIES_QUERY", "CpsGateway", "Order"]

log = logging.getLogger("transfertwin.web")
audit = logging.getLogger("transfertwin.web.audit")

# rdflib cannot GROUP_CONCAT(DISTINCT ...) a variable left unbound by an OPTIONAL: the
# capabilities (which not every asset has) come from a query of their own.
ASSETS_QUERY = """
PREFIX tt: <https://transfertwin.dev/ontology#>
SELECT ?id (GROUP_CONCAT(DISTINCT ?cls; separator="/") AS ?class) (SAMPLE(?t) AS ?type)
       (SAMPLE(?st) AS ?status) (SAMPLE(?os) AS ?state) (SAMPLE(?stn) AS ?station)
       (SAMPLE(?ep) AS ?endpoint) (SAMPLE(?sp) AS ?security) WHERE {
  ?a tt:assetId ?id .
  OPTIONAL { ?a a ?c . FILTER(STRSTARTS(STR(?c), STR(tt:))) BIND(STRAFTER(STR(?c), "#") AS ?cls) }
  OPTIONAL { ?a tt:assetType ?at . BIND(STRAFTER(STR(?at), "#") AS ?t) }
  OPTIONAL { ?a tt:status ?st }
  OPTIONAL { ?a tt:operationalState ?os }
  OPTIONAL { ?a tt:atStation ?s . BIND(STRAFTER(STR(?s), "/station/") AS ?stn) }
  OPTIONAL { ?a tt:endpoint ?ep }
  OPTIONAL { ?a tt:hasInterface ?i . ?i tt:securityPolicy ?sp }
} GROUP BY ?id ORDER BY ?id
"""
CAPABILITIES_QUERY = """
PREFIX tt: <https://transfertwin.dev/ontology#>
SELECT ?id ?cap WHERE {
  ?a tt:assetId ?id ; tt:hasCapability ?c . BIND(STRAFTER(STR(?c), "#") AS ?cap)
} ORDER BY ?id ?cap
"""

_LOCATION_QUERY = """
PREFIX tt: <https://transfertwin.dev/ontology#>
SELECT ?holder WHERE {
  { ?h tt:possesses ?o . } UNION { ?o tt:locatedAt ?h . }
  ?o tt:assetId "%s" . ?h tt:assetId ?holder .
}
"""
_ID = re.compile(r"^[A-Za-z0-9_]{1,64}$")
_KINDS = ("PhysicalAsset", "LogicalAsset", "VirtualModel")
_TYPE_LABEL = {"TypeA": "A", "TypeB": "B", "TypeC": "C", "TypeD": "D", "TypeE": "E",
               "TypeDE": "D/E"}  # fmt: skip


async def _node(s: AssetClient, *parts: str):
    """The node of an AAS element (``<asset>.<submodel>.<element>``) in a session."""
    ns = await s.client.get_namespace_index(NAMESPACE)
    return s.client.get_node(ua.NodeId(node_id(s.asset_id, *parts), ns))


def _jsonable(value: Any) -> Any:
    if isinstance(value, bool | int | str) or value is None:
        return value
    if isinstance(value, float):
        return value if value == value and abs(value) != float("inf") else None
    if isinstance(value, list | tuple):
        return [_jsonable(v) for v in value]
    return str(value)


@dataclass
class Order:
    """A transport order placed through the console."""

    id: str
    object: str
    source: str
    target: str
    submitted_utc: str
    client: str
    operation: str | None = None
    state: str = "submitted"  # submitted | running | finished | refused | lost
    outcome: str | None = None
    steps: list[dict[str, str]] = field(default_factory=list)

    def step(self, text: str) -> None:
        """Append a timestamped step (once per distinct text in a row)."""
        if not self.steps or self.steps[-1]["text"] != text:
            self.steps.append({"t": datetime.now(UTC).isoformat(timespec="milliseconds"),
                               "text": text})  # fmt: skip

    def public(self) -> dict[str, object]:
        """The order as the browser sees it."""
        return {"id": self.id, "object": self.object, "source": self.source,
                "target": self.target, "submitted_utc": self.submitted_utc,
                "operation": self.operation, "state": self.state, "outcome": self.outcome,
                "steps": list(self.steps)}  # fmt: skip


class CpsGateway:
    """Live view of a running CPS and its order desk (start with `start`, end with `stop`)."""

    def __init__(self, workdir: Path, period_s: float = 0.5) -> None:
        info = json.loads((workdir / "cps.json").read_text())
        self.workdir = workdir
        self.period_s = period_s
        self._insecure = bool(info.get("insecure"))
        self._cert_dir = Path(info["cert_dir"])
        self._creds: Credentials | None = (
            None if self._insecure else _load_credentials(Path(info["credentials_file"]))
        )
        self._assets: dict[str, dict[str, Any]] = {a["id"]: a for a in info["assets"]}
        self._sessions: dict[str, AssetClient] = {}
        self._kg: AssetClient | None = None
        self.values: dict[str, dict[str, Any]] = {a: {} for a in self._assets}
        self.online: dict[str, bool] = dict.fromkeys(self._assets, False)
        self.kg_rows: list[dict[str, Any]] = []
        self.kg_error: str | None = None
        self.orders: dict[str, Order] = {}
        self._order_ids = itertools.count(1)
        self._tasks: list[asyncio.Task] = []
        self._order_tasks: set[asyncio.Task] = set()
        self.updated = 0.0

    # -- life cycle -------------------------------------------------------------------------
    async def start(self) -> None:
        """Open the sessions (in the background: assets that are down come up later)."""
        if not self._insecure:
            for role in ("viewer", "operator"):  # once, before sessions race to make them
                await ensure_certificate(self._cert_dir, f"client-{role}")
        self._tasks = [asyncio.create_task(self._watch(aid)) for aid in self._assets]
        self._tasks.append(asyncio.create_task(self._watch_graph()))

    async def stop(self) -> None:
        """Close every session."""
        tasks = [*self._tasks, *self._order_tasks]
        for task in tasks:
            task.cancel()
        await asyncio.gather(*tasks, return_exceptions=True)
        self._tasks.clear()

    def _session(self, aid: str, role: str, timeout_s: float = 10.0):
        return connect(self._assets[aid]["endpoint"], aid, credentials=self._creds, role=role,
                       cert_dir=self._cert_dir, insecure=self._insecure,
                       timeout_s=timeout_s)  # fmt: skip

    async def _watch(self, aid: str) -> None:
        """Keep a viewer session with one asset; read its operational data each period."""
        while True:
            try:
                async with self._session(aid, "viewer", timeout_s=5.0) as s:
                    nodes = await self._variables(s, "OperationalData")
                    self._sessions[aid] = s
                    while True:
                        vals = await s.client.read_values([n for _, n in nodes]) if nodes else []
                        self.values[aid] = {k: _jsonable(v) for (k, _), v in
                                            zip(nodes, vals, strict=True)}  # fmt: skip
                        self.online[aid] = True
                        self.updated = time.time()
                        await asyncio.sleep(self.period_s)
            except asyncio.CancelledError:
                raise
            except Exception as exc:  # down, refused, timed out: offline, try again later
                log.debug("%s: %s", aid, exc)
            finally:
                self._sessions.pop(aid, None)
            self.online[aid] = False
            await asyncio.sleep(1.0)

    async def _watch_graph(self) -> None:
        """Keep an operator session with the knowledge graph; refresh the assets each second."""
        if "KG" not in self._assets:
            self.kg_error = "the CPS has no knowledge graph asset"
            return
        while True:
            try:
                async with self._session("KG", "operator") as kg:
                    self._kg = kg
                    while True:
                        rows = json.loads(await kg.call("Query", ASSETS_QUERY))
                        caps: dict[str, list[str]] = {}
                        for r in json.loads(await kg.call("Query", CAPABILITIES_QUERY)):
                            caps.setdefault(r["id"], []).append(r["cap"])
                        for r in rows:
                            r["capabilities"] = caps.get(r["id"], [])
                        self.kg_rows, self.kg_error = rows, None
                        await asyncio.sleep(1.0)
            except asyncio.CancelledError:
                raise
            except Exception as exc:
                self.kg_error = f"knowledge graph not answering ({type(exc).__name__})"
            finally:
                self._kg = None
            await asyncio.sleep(1.0)

    async def _query(self, sparql: str) -> list[dict[str, Any]]:
        if self._kg is not None:
            return json.loads(await self._kg.call("Query", sparql))
        async with self._session("KG", "operator") as kg:
            return json.loads(await kg.call("Query", sparql))

    # -- reads ----------------------------------------------------------------------------
    @staticmethod
    async def _variables(s: AssetClient, submodel: str) -> list[tuple[str, Any]]:
        sm = await _node(s, submodel)
        out = []
        for ref in await sm.get_children_descriptions():
            if ref.NodeClass == ua.NodeClass.Variable:
                out.append((ref.BrowseName.Name, s.client.get_node(ref.NodeId)))
        return out

    def assets(self) -> list[dict[str, Any]]:
        """Every asset of the CPS: its knowledge-graph description and whether it answers."""
        by_id = {r.get("id"): r for r in self.kg_rows}
        out = []
        for aid, a in self._assets.items():
            r = by_id.get(aid, {})
            classes = [c for c in str(r.get("class") or "").split("/") if c]
            kind = next((c for c in classes if c in _KINDS), a.get("kind"))
            caps = sorted(r.get("capabilities") or [])
            out.append({
                "id": aid,
                "class": a.get("class"),
                "kind": kind,
                "type": _TYPE_LABEL.get(str(r.get("type")), a.get("type")),
                "capabilities": caps,
                "station": r.get("station"),
                "status": r.get("status") or ("unknown" if self.kg_error else "offline"),
                "state": r.get("state"),
                "endpoint": r.get("endpoint") or a.get("endpoint"),
                "security": r.get("security") or a.get("security_policy"),
                "reachable": self.online.get(aid, False),
            })  # fmt: skip
        return out

    def live(self) -> dict[str, Any]:
        """The latest live values of every asset."""
        return {"t": self.updated, "online": dict(self.online), "values": self.values}

    async def aas(self, aid: str) -> list[dict[str, Any]]:
        """The asset's AAS as its server exposes it: submodels, their elements and values."""
        self._known(aid)
        s = self._sessions.get(aid)
        if s is None:
            raise LookupError(f"{aid} is not reachable right now")
        root = await _node(s)
        out = []
        for sm in await root.get_children_descriptions():
            if sm.NodeClass != ua.NodeClass.Object:
                continue
            node = s.client.get_node(sm.NodeId)
            elements, variables = [], []
            for ref in await node.get_children_descriptions():
                kind = {ua.NodeClass.Variable: "property", ua.NodeClass.Method: "operation",
                        ua.NodeClass.Object: "capability"}.get(ref.NodeClass)  # fmt: skip
                if kind is None:
                    continue
                el = {"id_short": ref.BrowseName.Name, "kind": kind}
                elements.append(el)
                if kind == "property":
                    variables.append((el, s.client.get_node(ref.NodeId)))
            vals = await s.client.read_values([n for _, n in variables]) if variables else []
            for (el, _), v in zip(variables, vals, strict=True):
                el["value"] = _jsonable(v)
            out.append({"id_short": sm.BrowseName.Name, "elements": elements})
        return out

    def _known(self, aid: str) -> dict[str, Any]:
        if not isinstance(aid, str) or not _ID.match(aid) or aid not in self._assets:
            raise LookupError(f"no asset {str(aid)[:64]!r} in the CPS")
        return self._assets[aid]

    def ids_of(self, cls: str) -> list[str]:
        """Asset ids of one class (from cps.json), e.g. 'transfer_unit', 'object'."""
        return [aid for aid, a in self._assets.items() if a.get("class") == cls]

    # -- orders ---------------------------------------------------------------------------
    def _unit(self, what: str, value: object) -> str:
        """A transfer unit id, or the unit standing at a station named by its id."""
        units = self.ids_of("transfer_unit")
        if not isinstance(value, str) or not _ID.match(value):
            raise InputError(f"{what} must be a transfer unit or station id, got {value!r:.70}")
        if value in units:
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
        if source is None:
            holders = [r["holder"] for r in await self._query(_LOCATION_QUERY % obj)]
            holders = [h for h in holders if h in self.ids_of("transfer_unit")]
            if not holders:
                raise InputError(f"where {obj} is is not known: give the source unit")
            source = holders[0]
        source = self._unit("source", source)
        if source == target:
            raise InputError(f"source and target are both {source}: nothing to transport")
        return obj, source, target

    async def submit(self, obj: str, source: str, target: str, client: str) -> Order:
        """Place a validated order with the TMS; it is followed in the background."""
        order = Order(f"w{next(self._order_ids)}", obj, source, target,
                      datetime.now(UTC).isoformat(timespec="seconds"), client)  # fmt: skip
        try:
            async with self._session("TMS", "operator", timeout_s=30) as tms:
                order.operation = str(await tms.call("SubmitTransportOperation", source,
                                                     target, obj))  # fmt: skip
        except ua.UaStatusCodeError as exc:
            reason = getattr(exc, "reason", None) or _status_text(exc)
            audit.info("order refused: %s %s -> %s from %s: %s", obj, source, target, client,
                       reason)  # fmt: skip
            raise InputError(f"the TMS refused the order: {reason}") from None
        self.orders[order.id] = order
        order.state = "running"
        order.step(f"submitted to the TMS as {order.operation}: {obj} {source} -> {target}")
        audit.info("order %s (%s): %s %s -> %s from %s", order.id, order.operation, obj,
                   source, target, client)  # fmt: skip
        task = asyncio.create_task(self._follow(order))
        self._order_tasks.add(task)
        task.add_done_callback(self._order_tasks.discard)
        return order

    async def _operation_status(self, op: str) -> dict[str, Any] | None:
        """The TMS's own record of an operation, where it offers OperationStatus."""
        try:
            async with self._session("TMS", "operator") as tms:
                return json.loads(await tms.call("OperationStatus", op))
        except ua.UaStatusCodeError:
            return None

    def _log_lines(self, op: str) -> list[str]:
        """The CPS log's lines of one operation (from its allocation to its end)."""
        path = self.workdir / "cps.log"
        if not path.is_file():
            return []
        lines = path.read_text(errors="replace").splitlines()
        start = next((i for i, ln in enumerate(lines) if f"TMS: {op} " in ln), None)
        if start is None:
            return []
        out = []
        for ln in lines[start:]:
            out.append(ln.split(" ", 2)[-1] if re.match(r"^\d{4}-\d\d-\d\d ", ln) else ln)
            if f"TMS: {op} finished" in ln:
                break
        return out

    async def _follow(self, order: Order, timeout_s: float = 1800.0) -> None:
        """Record the order's steps (the transport modules' state, the CPS log) to its end."""
        tms_status = True
        tms_ids = self.ids_of("transport_module")
        seen_log = 0
        deadline = time.monotonic() + timeout_s
        op = str(order.operation)
        while time.monotonic() < deadline:
            lines = self._log_lines(op)
            for tm in tms_ids if not lines else ():  # no CPS log: what the modules report
                v = self.values.get(tm, {})
                if v.get("State") not in (None, "", "idle") or v.get("DockedAt"):
                    docked = f", docked at {v['DockedAt']}" if v.get("DockedAt") else ""
                    task = f" ({v['CurrentTask']})" if v.get("CurrentTask") else ""
                    order.step(f"{tm}: {v.get('State')}{docked}{task}")
            for ln in lines[seen_log:]:
                order.step(ln)
            seen_log = len(lines)
            finished = next((ln for ln in lines if f"TMS: {op} finished: " in ln), None)
            status = await self._operation_status(op) if tms_status else None
            tms_status = status is not None
            if status is not None and status.get("state") == "finished":
                result = status.get("result") or {}
                order.outcome = str(result.get("status", "finished"))
            elif finished is not None:
                order.outcome = finished.split(f"TMS: {op} finished: ", 1)[1].strip()
            if order.outcome is not None:
                order.state = "finished"
                order.step(f"finished: {order.outcome}")
                audit.info("order %s (%s) finished: %s", order.id, op, order.outcome)
                return
            await asyncio.sleep(self.period_s)
        order.state = "lost"
        order.step(f"no outcome within {timeout_s:g} s")


def _status_text(exc: ua.UaStatusCodeError) -> str:
    with contextlib.suppress(Exception):
        return ua.StatusCode(exc.code).name
    return str(exc)
