"""The console's side of the CPS: the knowledge graph's view of the assets, live values
read over OPC UA, AAS browsing and transport orders.

The gateway reads ``cps.json`` and the credentials file of a running `transfertwin cps up`
and talks to the assets through the CPS client API (`transfertwin.cps.opcua.connect`): an
*viewer* session per asset for the live values and browsing, *operator* sessions for the
knowledge-graph queries and the orders (the only calls). Credentials stay in this process;
nothing returned to the browser carries them.

It follows the floor as it changes: ``cps.json`` is read again every second, and a floor
started again in the same folder (new ports) is picked up; the knowledge graph's ``Status``
names the assets that joined at runtime and those whose lease expired; a session that
breaks is opened again (an asset process that restarts keeps its endpoint); values of an
asset that stopped answering are kept but marked stale, with the time of the last read and
the reason.
"""

from __future__ import annotations

import asyncio
import json
import logging
import re
import time
from pathlib import Path
from typing import Any

from asyncua import ua

from transfertwin._atomic import write_atomic
from transfertwin._errors import InputError
from transfertwin.cps.opcua import (
    NAMESPACE,
    AssetClient,
    Credentials,
    OperationRefused,
    connect,
    ensure_certificate,
    node_id,
)
from transfertwin.cps.opcua import load_credentials as _load_credentials
from transfertwin.web._display import display_values, unreachable_text, value_text
from transfertwin.web._floor import (
    FloorInfo,
    asset_condition,
    merge_assets,
    order_rows,
    read_floor_info,
)
from transfertwin.web._orders import Order, OrderDesk

__all__ = ["ASSETS_QUERY", "CAPABILITIES_QUERY", "CpsGateway", "Order"]

log = logging.getLogger("transfertwin.web")

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

_ID = re.compile(r"^[A-Za-z0-9_]{1,64}$")
#: The longest query the console passes to the knowledge graph.
QUERY_MAX_CHARS = 4000
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


class CpsGateway(OrderDesk):
    """Live view of a running CPS and its order desk (start with `start`, end with `stop`)."""

    def __init__(self, workdir: Path, period_s: float = 0.5) -> None:
        info = read_floor_info(workdir)
        if info is None:
            raise InputError(f"{workdir}: no CPS there (no cps.json)")
        self.workdir = workdir
        self.period_s = period_s
        self.info = info
        self._creds: Credentials | None = None
        self._assets: dict[str, dict[str, Any]] = {}
        self._watchers: dict[str, tuple[str, asyncio.Task]] = {}
        self._sessions: dict[str, AssetClient] = {}
        self._kg: AssetClient | None = None
        self.values: dict[str, dict[str, Any]] = {}
        self.online: dict[str, bool] = {}  # a viewer session reads the asset now
        self.errors: dict[str, str] = {}  # why the last session attempt failed
        self.seen: dict[str, float] = {}  # time of the last good read (s since the epoch)
        self.kg_rows: list[dict[str, Any]] = []
        self.kg_status: dict[str, dict[str, Any]] | None = None  # the graph's Status
        self.kg_error: str | None = None
        self.floor_error: str | None = None
        self.ledger: list[dict[str, Any]] | None = None  # the TMS's operations
        self.tms_error: str | None = None
        self.orders: dict[str, Order] = _kept_orders(workdir / ORDERS_FILE)
        self._tasks: list[asyncio.Task] = []
        self._floor_tasks: list[asyncio.Task] = []
        self._order_tasks: set[asyncio.Task] = set()
        self.updated = 0.0
        self._use(info)

    def _use(self, info: FloorInfo) -> None:
        """Take a (new) cps.json: its credentials, certificates and assets."""
        self.info = info
        self._creds = None if info.insecure else _load_credentials(info.credentials_file)
        self._assets = merge_assets(info.assets, None)

    # -- life cycle -------------------------------------------------------------------------
    async def start(self) -> None:
        """Open the sessions (in the background: assets that are down come up later)."""
        await self._certificates()
        self._sync_watchers()
        self._start_floor_tasks()
        self._tasks.append(asyncio.create_task(self._discover()))

    async def _certificates(self) -> None:
        if not self.info.insecure:
            for role in {self.info.reader_role, "operator"}:  # before sessions race to make them
                await ensure_certificate(self.info.cert_dir, f"client-{role}")

    def _start_floor_tasks(self) -> None:
        self._floor_tasks = [
            asyncio.create_task(self._watch_graph()),
            asyncio.create_task(self._watch_ledger()),
        ]

    async def stop(self) -> None:
        """Close every session."""
        tasks = [*self._tasks, *self._floor_tasks, *self._order_tasks,
                 *(t for _, t in self._watchers.values())]  # fmt: skip
        for task in tasks:
            task.cancel()
        await asyncio.gather(*tasks, return_exceptions=True)
        self._tasks.clear()
        self._floor_tasks.clear()
        self._watchers.clear()

    def _session(self, aid: str, role: str, timeout_s: float = 10.0, endpoint: str | None = None):
        return connect(endpoint or self._assets[aid]["endpoint"], aid, credentials=self._creds,
                       role=role, cert_dir=self.info.cert_dir, insecure=self.info.insecure,
                       timeout_s=timeout_s)  # fmt: skip

    # -- following the floor ----------------------------------------------------------------
    async def _discover(self) -> None:
        """Read cps.json again each second; a new one (a CPS started again) is taken."""
        while True:
            await asyncio.sleep(1.0)
            info = read_floor_info(self.workdir)
            if info is None:
                self.floor_error = (f"the CPS is not running (no cps.json in {self.workdir}); "
                                    "start it with 'transfertwin cps up'")  # fmt: skip
                continue
            self.floor_error = None
            if info.stamp != self.info.stamp:
                await self._restart(info)
            self._sync_watchers()

    async def _restart(self, info: FloorInfo) -> None:
        """A new cps.json: new endpoints (and maybe certificates); sessions open again."""
        log.info("%s: cps.json changed; following the new floor", self.workdir)
        try:
            self._use(info)
            await self._certificates()
        except (OSError, ValueError, KeyError, InputError) as exc:  # half written: next time
            log.debug("cps.json not usable yet: %s", exc)
            return
        for task in self._floor_tasks:
            task.cancel()
        await asyncio.gather(*self._floor_tasks, return_exceptions=True)
        self.kg_rows, self.kg_status, self.ledger = [], None, None
        self.kg_error = self.tms_error = "connecting to the restarted CPS"
        self._start_floor_tasks()

    def _sync_watchers(self) -> None:
        """One watcher per asset and endpoint: new assets get one, a changed endpoint a new
        one, an asset gone from the floor loses its own."""
        status = list(self.kg_status.values()) if self.kg_status else None
        self._assets = merge_assets(self.info.assets, status)
        for aid, (endpoint, task) in list(self._watchers.items()):
            if self._assets.get(aid, {}).get("endpoint") != endpoint:
                task.cancel()
                del self._watchers[aid]
                self.online[aid] = False
        for aid in [a for a in self.values if a not in self._assets]:
            for table in (self.values, self.online, self.errors, self.seen):
                table.pop(aid, None)
        for aid, a in self._assets.items():
            if aid not in self._watchers:
                self.values.setdefault(aid, {})
                self.online.setdefault(aid, False)
                task = asyncio.create_task(self._watch(aid, a["endpoint"]))
                self._watchers[aid] = (a["endpoint"], task)

    async def _watch(self, aid: str, endpoint: str) -> None:
        """Keep a viewer session with one asset; read its operational data each period."""
        while True:
            try:
                async with self._session(aid, self.info.reader_role, 5.0, endpoint) as s:
                    nodes = await self._variables(s, "OperationalData")
                    self._sessions[aid] = s
                    while True:
                        vals = (await asyncio.wait_for(s.client.read_values(
                            [n for _, n in nodes]), 5.0) if nodes else [])  # fmt: skip
                        self.values[aid] = {k: _jsonable(v) for (k, _), v in
                                            zip(nodes, vals, strict=True)}  # fmt: skip
                        self.online[aid], self.seen[aid] = True, time.time()
                        self.errors.pop(aid, None)
                        self.updated = time.time()
                        await asyncio.sleep(self.period_s)
            except asyncio.CancelledError:
                raise
            except Exception as exc:  # down, refused, timed out: offline, try again later
                self.errors[aid] = type(exc).__name__
                log.debug("%s: %s", aid, exc)
            finally:
                self._sessions.pop(aid, None)
            self.online[aid] = False
            await asyncio.sleep(1.0)

    async def _watch_graph(self) -> None:
        """Keep an operator session with the knowledge graph; refresh the assets each second
        (and, on a process floor, the graph's Status: who is online, who joined)."""
        if "KG" not in self._assets:
            self.kg_error = "the CPS has no knowledge graph asset"
            return
        while True:
            try:
                async with self._session("KG", "operator") as kg:
                    self._kg = kg
                    while True:
                        await self._read_graph(kg)
                        await asyncio.sleep(1.0)
            except asyncio.CancelledError:
                raise
            except Exception as exc:
                self.kg_error = f"the knowledge graph is {unreachable_text(type(exc).__name__)}"
                self.kg_rows, self.kg_status = [], None  # nothing stale shown as current
            finally:
                self._kg = None
            await asyncio.sleep(1.0)

    async def _read_graph(self, kg: AssetClient) -> None:
        rows = json.loads(await kg.call("Query", ASSETS_QUERY))
        caps: dict[str, list[str]] = {}
        for r in json.loads(await kg.call("Query", CAPABILITIES_QUERY)):
            caps.setdefault(r["id"], []).append(r["cap"])
        for r in rows:
            r["capabilities"] = caps.get(r["id"], [])
        status = json.loads(await kg.call("Status"))["assets"]
        self.kg_status = {r["id"]: r for r in status}
        if set(self.kg_status) - set(self._assets):
            self._sync_watchers()  # an asset joined at runtime
        self.kg_rows, self.kg_error = rows, None

    async def _watch_ledger(self) -> None:
        """The TMS's ledger (operations with their histories) each second."""
        while True:
            try:
                async with self._session("TMS", "operator") as tms:
                    while True:
                        self.ledger = json.loads(await tms.call("Ledger"))["operations"]
                        self.tms_error = None
                        await asyncio.sleep(1.0)
            except asyncio.CancelledError:
                raise
            except Exception as exc:
                self.tms_error = f"the TMS is {unreachable_text(type(exc).__name__)}"
            await asyncio.sleep(1.0)

    async def _query(self, sparql: str) -> list[dict[str, Any]]:
        if self._kg is not None:
            return json.loads(await self._kg.call("Query", sparql))
        async with self._session("KG", "operator") as kg:
            return json.loads(await kg.call("Query", sparql))

    async def query(self, sparql: str) -> list[dict[str, Any]]:
        """The knowledge graph's answer to a SPARQL SELECT query (its ``Query``; it refuses
        anything else); InputError with the graph's reason when it refuses."""
        if not isinstance(sparql, str) or not sparql.strip() or len(sparql) > QUERY_MAX_CHARS:
            raise InputError(f"a query must be 1..{QUERY_MAX_CHARS} characters of SPARQL")
        try:
            return await self._query(sparql)
        except OperationRefused as exc:
            first = (exc.reason.strip().splitlines() or [""])[0][:300]
            raise InputError(f"the knowledge graph refused the query: {first}") from None

    # -- reads ----------------------------------------------------------------------------
    @staticmethod
    async def _variables(s: AssetClient, submodel: str) -> list[tuple[str, Any]]:
        sm = await _node(s, submodel)
        out = []
        for ref in await sm.get_children_descriptions():
            if ref.NodeClass == ua.NodeClass.Variable:
                out.append((ref.BrowseName.Name, s.client.get_node(ref.NodeId)))
        return out

    def condition(self, aid: str) -> tuple[bool, str | None]:
        """(online, reason offline) of an asset (see `asset_condition`)."""
        kg_row = (self.kg_status or {}).get(aid)
        standby = bool(self._assets.get(aid, {}).get("standby"))
        return asset_condition(self.online.get(aid, False), self.errors.get(aid), kg_row,
                               self.floor_error, standby)  # fmt: skip

    def _kg_status_word(self, aid: str, row: dict[str, Any]) -> str:
        if self.floor_error or self.kg_error:
            return "unknown"
        if self.kg_status is not None and aid in self.kg_status:
            return "online" if self.kg_status[aid].get("online") else "offline"
        return row.get("status") or "not joined"

    def assets(self) -> list[dict[str, Any]]:
        """Every asset of the floor: its knowledge-graph description, whether it answers and
        why not."""
        by_id = {r.get("id"): r for r in self.kg_rows}
        out = []
        for aid, a in self._assets.items():
            r = by_id.get(aid, {})
            classes = [c for c in str(r.get("class") or "").split("/") if c]
            kind = next((c for c in classes if c in _KINDS), a.get("kind"))
            online, reason = self.condition(aid)
            st = (self.kg_status or {}).get(aid, {})
            out.append({
                "id": aid,
                "class": a.get("class"),
                "kind": kind,
                "type": _TYPE_LABEL.get(str(r.get("type")), a.get("type")),
                "capabilities": sorted(r.get("capabilities") or []),
                "station": r.get("station"),
                "status": self._kg_status_word(aid, r),
                "state": r.get("state") if not self.kg_error else None,
                "endpoint": r.get("endpoint") or a.get("endpoint"),
                "security": r.get("security") or a.get("security_policy"),
                "reachable": online,
                "reason": reason,
                "pid": st.get("pid"),
                "joined": bool(a.get("joined")),
            })  # fmt: skip
        return out

    def live(self) -> dict[str, Any]:
        """The latest values of every asset; an offline asset's are its last ones, marked
        stale with the time they were read and why it is offline."""
        conditions = {aid: self.condition(aid) for aid in self._assets}
        return {"t": self.updated,
                "online": {aid: c[0] for aid, c in conditions.items()},
                "reason": {aid: c[1] for aid, c in conditions.items() if not c[0]},
                "stale": [aid for aid, c in conditions.items()
                          if not c[0] and self.values.get(aid)],
                "seen": {aid: self.seen[aid] for aid in self._assets if aid in self.seen},
                "values": {aid: self.values.get(aid, {}) for aid in self._assets},
                "display": {aid: display_values(self.values.get(aid, {}))
                            for aid in self._assets},
                "kg_error": self.floor_error or self.kg_error}  # fmt: skip

    async def aas(self, aid: str) -> list[dict[str, Any]]:
        """The asset's AAS as its server exposes it: submodels, their elements and values."""
        self._known(aid)
        s = self._sessions.get(aid)
        online, reason = self.condition(aid)
        if s is None or not online:
            raise LookupError(f"{aid} is offline: {reason or 'not reachable right now'}")
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
                el["text"] = value_text(el["id_short"], el["value"])
            out.append({"id_short": sm.BrowseName.Name, "elements": elements})
        return out

    async def read_variables(self, aid: str, keys: list[str]) -> dict[str, Any]:
        """Values of an asset's variables, read now over its viewer session.

        Args:
            aid: The asset.
            keys: Node keys ``<submodel>.<element path>``, e.g. ``OperationalData.State``.

        Returns:
            Key -> value of each variable the server has (one it lacks is left out).

        Raises:
            LookupError: The asset is unknown or offline.
        """
        self._known(aid)
        s = self._sessions.get(aid)
        online, reason = self.condition(aid)
        if s is None or not online:
            raise LookupError(f"{aid} is offline: {reason or 'not reachable right now'}")
        ns = await s.client.get_namespace_index(NAMESPACE)
        nodes = [s.client.get_node(ua.NodeId(node_id(aid, k), ns)) for k in keys]
        read = await asyncio.wait_for(s.client.read_attributes(nodes), 5.0) if nodes else []
        return {k: _jsonable(r.Value.Value) for k, r in zip(keys, read, strict=True)
                if r.StatusCode.is_good() and r.Value is not None}  # fmt: skip

    def _known(self, aid: str) -> dict[str, Any]:
        if not isinstance(aid, str) or not _ID.match(aid) or aid not in self._assets:
            raise LookupError(f"no asset {str(aid)[:64]!r} in the CPS")
        return self._assets[aid]

    def ids_of(self, cls: str) -> list[str]:
        """Asset ids of one generic class (from cps.json), e.g. 'transfer_unit', 'object': a
        class of its own counts as the one it runs as (``role_class``, a buffer station as
        a transfer unit)."""
        return [aid for aid, a in self._assets.items()
                if a.get("role_class", a.get("class")) == cls]  # fmt: skip

    # -- orders: the floor's operations by their unique id ----------------------------------
    def order_rows(self) -> list[dict[str, Any]]:
        """The Orders tab: every operation of the floor's TMS (placed here or from the
        command line), keyed by its operation id, with who placed it."""
        return order_rows(self.ledger or [], [o.public() for o in self.orders.values()])

    def order(self, oid: str) -> dict[str, Any]:
        """One row of `order_rows`, by console id or operation id."""
        for row in self.order_rows():
            if oid in (row["id"], row.get("operation")):
                return row
        raise LookupError(f"no order {oid[:40]!r}")

    async def _tms_call(self, operation: str, *args: object) -> Any:
        async with self._session("TMS", "operator", timeout_s=30) as tms:
            return await tms.call(operation, *args)

    def _keep_orders(self) -> None:
        doc = [o.record() for o in self.orders.values()]
        write_atomic(self.workdir / ORDERS_FILE, json.dumps(doc, indent=1) + "\n")

    def _module_sources(self) -> list[str]:
        # the TMS takes an order onward from a module holding the object
        return self.ids_of("transport_module")

    def destination_groups(self) -> list[str]:
        return [g for g, _ in self.info.groups]

    def kpis(self) -> dict[str, Any] | None:
        """The TMS's KPIs as it publishes them (`KpisJson`), or None."""
        text = self.values.get("TMS", {}).get("KpisJson")
        try:
            return json.loads(text) if text else None
        except ValueError:
            return None


#: The console's own orders, kept in the floor's work folder (`Order.record`).
ORDERS_FILE = "console-orders.json"


def _kept_orders(path: Path) -> dict[str, Order]:
    """The console's orders kept in `path` (none when it is missing or unreadable)."""
    try:
        doc = json.loads(path.read_text())
        orders = [Order.from_record(rec) for rec in doc]
    except (OSError, ValueError, KeyError, TypeError):
        return {}
    return {o.id: o for o in orders}
