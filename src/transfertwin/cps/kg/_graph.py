"""The knowledge graph: the descriptive layer as a logical asset (Sec. 3.3).

Assets join with an RDF description (built by `describe` from an `AssetDescriptor`, or
sent by the asset itself), which must pass the SHACL shapes KG-1 … KG-11 before any of
it enters the graph. The graph holds the ontology (TBox) and the asset descriptions
(ABox) together, so queries may follow ``rdfs:subClassOf``.

Leave semantics: `KnowledgeGraph.leave` keeps the asset's static description (classes,
type, capabilities, station, interface, virtual-model link) so it can be looked up and
rejoin, marks it ``tt:status "offline"`` and drops its dynamic relations in both
directions (``tt:dockedAt``, ``tt:possesses``), its ``tt:operationalState`` and, for an
object, its ``tt:locatedAt``; objects lying on an asset that leaves stay located there
(they have not moved). Every named query counts online assets only. A later `join`
replaces the asset's own triples with the new description.
"""

from __future__ import annotations

import logging
import re
import threading
from collections.abc import Callable, Iterable
from typing import Literal

from rdflib import RDF, Graph, URIRef
from rdflib import Literal as RdfLiteral
from rdflib.plugins.sparql.sparql import Query

from transfertwin._errors import InputError
from transfertwin.cps.aas import AssetDescriptor, AssetKind, Capability
from transfertwin.cps.kg._describe import (
    ROLE_CLASSES,
    TT,
    TYPE_IRIS,
    asset_iri,
    check_id,
    describe,
    load_ontology,
    station_iri,
)
from transfertwin.cps.kg._queries import (
    IDLE_TRANSPORT_MODULES,
    OBJECT_LOCATIONS,
    RECEIVERS_AT,
    VIRTUAL_MODELS_OF,
    prepared,
    read_only_select,
)
from transfertwin.cps.kg._validate import validate_description

__all__ = ["ChangeKind", "ChangeListener", "KnowledgeGraph"]

_log = logging.getLogger(__name__)

ChangeKind = Literal["join", "leave", "update"]
ChangeListener = Callable[[ChangeKind, str], None]

_STATE = re.compile(r"^[a-z][a-z_]*$")
_ROLE_NAMES = {iri: name for name, iri in ROLE_CLASSES.items()}
_TYPE_NAMES = {iri: ptype.value for ptype, iri in TYPE_IRIS.items()}
_KINDS = (
    (TT.VirtualModel, AssetKind.VIRTUAL_MODEL),
    (TT.PhysicalAsset, AssetKind.PHYSICAL),
    (TT.LogicalAsset, AssetKind.LOGICAL),
)


class KnowledgeGraph:
    """Thread-safe knowledge graph of the CPS; itself a logical asset (Sec. 3.3).

    Args:
        asset_id: Id of the knowledge graph asset, which joins itself on creation.
        endpoint: OPC UA endpoint of the knowledge graph's own interface, if any.
        security_policy: Security policy of that endpoint.
    """

    describe = staticmethod(describe)

    def __init__(
        self,
        asset_id: str = "KG",
        *,
        endpoint: str | None = None,
        security_policy: str | None = None,
    ) -> None:
        self._lock = threading.RLock()
        self._graph = load_ontology()
        self._graph.bind("tt", TT)
        self._listeners: list[ChangeListener] = []
        self.asset_id = check_id(asset_id, "asset id")
        own = AssetDescriptor(
            asset_id, AssetKind.LOGICAL, "knowledge_graph", capabilities=(Capability.KNOWLEDGE,)
        )
        self.join(own, endpoint=endpoint, security_policy=security_policy)

    # --- membership ---------------------------------------------------------------------
    def join(
        self,
        desc: AssetDescriptor,
        *,
        endpoint: str | None = None,
        security_policy: str | None = None,
        state: str | None = "idle",
    ) -> None:
        """Validate an asset's description (KG-1 … KG-11) and add it; see `describe`.

        A joining asset is 'idle' unless ``state`` says otherwise (None: unknown).
        """
        description = describe(
            desc, endpoint=endpoint, security_policy=security_policy, state=state
        )
        self.join_graph(description)

    def join_graph(self, description: Graph) -> str:
        """Validate a description sent by an asset and add it, replacing an earlier one.

        Returns:
            The asset id.

        Raises:
            InputError: The description violates a shape (the message names the asset
                and the first violation), is not online, or describes nodes other than
                the asset, its interfaces and its stations. Nothing is added then.
        """
        with self._lock:
            node, name = validate_description(description, self._graph)
            self._remove_own(node)
            for triple in description:
                self._graph.add(triple)
        self._notify("join", name)
        return name

    def leave(self, asset_id: str) -> None:
        """Mark an asset offline and drop its dynamic relations (see module docstring).

        Leaving twice is a no-op; an unknown asset raises `InputError`.
        """
        with self._lock:
            node = self._known(asset_id)
            if self._graph.value(node, TT.status) == RdfLiteral("offline"):
                return
            self._graph.set((node, TT.status, RdfLiteral("offline")))
            self._graph.remove((node, TT.operationalState, None))
            for prop in (TT.dockedAt, TT.possesses):
                self._graph.remove((node, prop, None))
                self._graph.remove((None, prop, node))
            self._graph.remove((node, TT.locatedAt, None))
        self._notify("leave", asset_id)

    # --- dynamic state ------------------------------------------------------------------
    def set_docked(self, tm_id: str, tu_id: str | None) -> None:
        """Record that transport module ``tm_id`` is docked at ``tu_id`` (None: undocked)."""
        with self._lock:
            tm = self._online(tm_id, TT.TransportModule)
            tu = self._online(tu_id, TT.TransferUnit) if tu_id is not None else None
            self._graph.remove((tm, TT.dockedAt, None))
            if tu is not None:
                self._graph.add((tm, TT.dockedAt, tu))
        self._notify("update", tm_id)

    def set_possesses(self, asset_id: str, object_ids: Iterable[str]) -> None:
        """Replace the set of objects an online asset possesses (lying on it).

        Objects need not have joined; an id of a known asset that is not a
        ``tt:Object`` is refused. Possession is not exclusive: during a transfer both
        partners may hold the object.
        """
        ids = [check_id(o, "object id") for o in object_ids]
        objects = [asset_iri(o) for o in ids]
        with self._lock:
            node = self._online(asset_id)
            for obj, oid in zip(objects, ids, strict=True):
                known = (obj, TT.assetId, None) in self._graph
                if known and (obj, RDF.type, TT.Object) not in self._graph:
                    raise InputError(f"{oid} is an asset but not an object")
            self._graph.remove((node, TT.possesses, None))
            for obj in objects:
                self._graph.add((node, TT.possesses, obj))
        self._notify("update", asset_id)

    def set_location(self, object_id: str, holder_id: str) -> None:
        """Record that object ``object_id`` lies on asset ``holder_id`` (``tt:locatedAt``,
        at most one per object: the new location replaces the old one).

        Raises:
            InputError: The object is unknown or not a ``tt:Object``, or the holder is
                unknown or offline.
        """
        with self._lock:
            obj = self._known(object_id)
            if (obj, RDF.type, TT.Object) not in self._graph:
                raise InputError(f"{object_id} is an asset but not an object")
            holder = self._online(holder_id)
            self._graph.set((obj, TT.locatedAt, holder))
        self._notify("update", object_id)

    def locations(self) -> dict[str, str]:
        """Object id -> id of the asset it is located at, for every located object."""
        rows = self._select(prepared(OBJECT_LOCATIONS), {})
        return {row["object"]: row["holder"] for row in rows}

    def set_state(self, asset_id: str, state: str) -> None:
        """Set the operational state of an online asset, e.g. 'idle', 'busy'."""
        if not isinstance(state, str) or not _STATE.match(state):
            raise InputError(f"a state is lower-case letters and '_', got {state!r}")
        with self._lock:
            node = self._online(asset_id)
            self._graph.set((node, TT.operationalState, RdfLiteral(state)))
        self._notify("update", asset_id)

    # --- reading ------------------------------------------------------------------------
    def assets(self, *, online_only: bool = False) -> list[dict[str, str | None]]:
        """All known assets, sorted by id.

        Returns:
            One dict per asset with keys 'id', 'kind' (AssetKind value), 'class' (asset
            class name), 'type' (Table 3.1 type or None), 'endpoint', 'status', 'state'.
        """
        with self._lock:
            rows = [self._row(node) for node in set(self._graph.subjects(TT.assetId, None))]
        if online_only:
            rows = [row for row in rows if row["status"] == "online"]
        return sorted(rows, key=lambda row: row["id"] or "")

    def triples(self) -> int:
        """Number of triples, ontology included."""
        with self._lock:
            return len(self._graph)

    def query(self, sparql: str) -> list[dict[str, str]]:
        """Answer a read-only SELECT query; prefixes tt, rdf, rdfs are predeclared.

        Returns:
            One dict per solution: variable name -> lexical value (unbound omitted).

        Raises:
            InputError: Updates, non-SELECT queries, SERVICE clauses, syntax errors.
        """
        return self._select(read_only_select(sparql), {})

    def receivers_at(self, station: str) -> list[str]:
        """Ids of online assets that can receive an object at ``station`` (sorted)."""
        rows = self._select(prepared(RECEIVERS_AT), {"station": station_iri(station)})
        return [row["id"] for row in rows]

    def virtual_models_of(self, asset_id: str) -> list[str]:
        """Ids of the online virtual models that mirror ``asset_id`` (sorted)."""
        rows = self._select(prepared(VIRTUAL_MODELS_OF), {"target": asset_iri(asset_id)})
        return [row["id"] for row in rows]

    def idle_transport_modules(self) -> list[str]:
        """Ids of online transport modules in operational state 'idle' (sorted)."""
        return [row["id"] for row in self._select(prepared(IDLE_TRANSPORT_MODULES), {})]

    def to_turtle(self) -> str:
        """The whole graph (ontology and assets) as Turtle."""
        with self._lock:
            return self._graph.serialize(format="turtle")

    # --- change notification ------------------------------------------------------------
    def subscribe(self, listener: ChangeListener) -> Callable[[], None]:
        """Call ``listener(kind, asset_id)`` after every join, leave and update.

        Listeners run on the caller's thread after the lock is released; an exception in
        one is logged and does not undo the change.

        Returns:
            A function that unsubscribes the listener.
        """
        with self._lock:
            self._listeners.append(listener)

        def unsubscribe() -> None:
            with self._lock:
                if listener in self._listeners:
                    self._listeners.remove(listener)

        return unsubscribe

    # --- internals ----------------------------------------------------------------------
    def _notify(self, kind: ChangeKind, asset_id: str) -> None:
        with self._lock:
            listeners = list(self._listeners)
        for listener in listeners:
            try:
                listener(kind, asset_id)
            except Exception:
                _log.exception("knowledge-graph listener failed on %s %s", kind, asset_id)

    def _select(self, query: Query, bindings: dict[str, URIRef]) -> list[dict[str, str]]:
        with self._lock:
            result = self._graph.query(query, initBindings=bindings)
            return [{k: str(v) for k, v in row.asdict().items()} for row in result]

    def _known(self, asset_id: str) -> URIRef:
        node = asset_iri(asset_id)
        if (node, TT.assetId, None) not in self._graph:
            raise InputError(f"unknown asset {asset_id!r}")
        return node

    def _online(self, asset_id: str, cls: URIRef | None = None) -> URIRef:
        node = self._known(asset_id)
        if self._graph.value(node, TT.status) != RdfLiteral("online"):
            raise InputError(f"asset {asset_id} is offline")
        if cls is not None and (node, RDF.type, cls) not in self._graph:
            raise InputError(f"asset {asset_id} is not a {cls.fragment}")
        return node

    def _remove_own(self, node: URIRef) -> None:
        """Forget an asset's description: its node and its own nodes under its IRI (its
        interfaces, its capabilities' constraints)."""
        for own in list(self._graph.objects(node, None)):
            if isinstance(own, URIRef) and str(own).startswith(f"{node}/"):
                self._graph.remove((own, None, None))
        self._graph.remove((node, None, None))

    def _row(self, node: URIRef) -> dict[str, str | None]:
        types = set(self._graph.objects(node, RDF.type))
        kind = next((k.value for cls, k in _KINDS if cls in types), None)
        role = next((_ROLE_NAMES[t] for t in sorted(types) if t in _ROLE_NAMES), None)
        ptype = self._graph.value(node, TT.assetType)

        def text(prop: URIRef) -> str | None:
            value = self._graph.value(node, prop)
            return None if value is None else str(value)

        return {
            "id": text(TT.assetId),
            "kind": kind,
            "class": role,
            "type": _TYPE_NAMES.get(ptype) if ptype is not None else None,
            "endpoint": text(TT.endpoint),
            "status": text(TT.status),
            "state": text(TT.operationalState),
        }
