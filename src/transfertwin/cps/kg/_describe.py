"""Vocabulary of the descriptive layer and asset descriptions in RDF (Sec. 3.3).

The ontology and the SHACL shapes are Turtle files shipped in
``transfertwin/data/ontology``. Asset IRIs are ``https://transfertwin.dev/ids/asset/<id>``,
stations ``https://transfertwin.dev/ids/station/<id>``, an asset's OPC UA interface
``<asset IRI>/interface/opcua``.
"""

from __future__ import annotations

import functools
import re
from importlib import resources

from rdflib import RDF, Graph, Literal, Namespace, URIRef

from transfertwin._errors import InputError
from transfertwin.cps.aas import (
    AssetDescriptor,
    AssetKind,
    Capability,
    PhysicalType,
    capability_specs,
)

__all__ = [
    "ASSET_CLASSES",
    "ASSET_NS",
    "CAPABILITY_IRIS",
    "KIND_CLASSES",
    "ROLE_CLASSES",
    "STATION_NS",
    "TT",
    "TYPE_IRIS",
    "asset_iri",
    "check_id",
    "describe",
    "load_ontology",
    "station_iri",
]

TT = Namespace("https://transfertwin.dev/ontology#")
ASSET_NS = "https://transfertwin.dev/ids/asset/"
STATION_NS = "https://transfertwin.dev/ids/station/"
_ID = re.compile(r"^[A-Za-z0-9_]+$")

KIND_CLASSES: dict[AssetKind, URIRef] = {
    AssetKind.PHYSICAL: TT.PhysicalAsset,
    AssetKind.LOGICAL: TT.LogicalAsset,
    AssetKind.VIRTUAL_MODEL: TT.VirtualModel,
}
ROLE_CLASSES: dict[str, URIRef] = {
    "transfer_unit": TT.TransferUnit,
    "transport_module": TT.TransportModule,
    "object": TT.Object,
    "transport_module_system": TT.TransportModuleSystem,
    "experiment_manager": TT.ExperimentManager,
    "props": TT.PropS,
    "knowledge_graph": TT.KnowledgeGraphAsset,
}
ASSET_CLASSES: frozenset[URIRef] = frozenset(
    {TT.Asset, *KIND_CLASSES.values(), *ROLE_CLASSES.values()}
)
TYPE_IRIS: dict[PhysicalType, URIRef] = {
    PhysicalType.A: TT.TypeA,
    PhysicalType.B: TT.TypeB,
    PhysicalType.C: TT.TypeC,
    PhysicalType.D: TT.TypeD,
    PhysicalType.E: TT.TypeE,
    PhysicalType.D_E: TT.TypeDE,
}
CAPABILITY_IRIS: dict[Capability, URIRef] = {
    Capability.TRANSFER: TT.Transfer,
    Capability.TRANSPORT: TT.Transport,
    Capability.SENSE: TT.Sense,
    Capability.ALLOCATE: TT.Allocate,
    Capability.EXPERIMENT: TT.Experiment,
    Capability.FUSE_POSES: TT.FusePoses,
    Capability.KNOWLEDGE: TT.Knowledge,
}


def check_id(value: str, what: str) -> str:
    """Return ``value`` if it is a non-empty id of letters, digits and '_'.

    Raises:
        InputError: Otherwise (ids become IRIs, so nothing else may pass).
    """
    if not isinstance(value, str) or not _ID.match(value):
        raise InputError(f"{what} must be letters, digits or '_', got {value!r}")
    return value


def asset_iri(asset_id: str) -> URIRef:
    """IRI of an asset, e.g. ``https://transfertwin.dev/ids/asset/TU_A``."""
    return URIRef(ASSET_NS + check_id(asset_id, "asset id"))


def station_iri(station: str) -> URIRef:
    """IRI of a station, e.g. ``https://transfertwin.dev/ids/station/C``."""
    return URIRef(STATION_NS + check_id(station, "station id"))


def interface_iri(asset_id: str) -> URIRef:
    """IRI of an asset's OPC UA interface node."""
    return URIRef(f"{asset_iri(asset_id)}/interface/opcua")


def describe(
    desc: AssetDescriptor,
    *,
    endpoint: str | None = None,
    security_policy: str | None = None,
    status: str = "online",
    state: str | None = None,
) -> Graph:
    """RDF description of one asset, as it would enter the knowledge graph (pure).

    The description is not validated here; `KnowledgeGraph.join` runs the shapes.

    Args:
        desc: The asset.
        endpoint: OPC UA endpoint URL of its virtual representation, if it has one.
        security_policy: OPC UA security policy of that endpoint, e.g. 'Basic256Sha256'.
        status: 'online' or 'offline'.
        state: Operational state ('idle', 'busy', ...), or None when unknown.

    An asset of a class the code does not know is typed by the generic class it runs as
    (`AssetDescriptor.role_class`: by its capabilities); ``tt:assetClass`` keeps its own.
    Each constraint of a capability it offers (`capability_specs`: its class's, or its own
    values) is a node ``<asset IRI>/capability/<capability>/<constraint>`` with
    ``tt:ofCapability``, ``tt:constraint`` (the ontology's individual) and ``tt:value``:
    what partners are chosen by (`transfertwin.cps.node.find_partners`).

    Returns:
        A new graph with the asset node, its interface node, its station node and its
        capabilities' constraint nodes.

    Raises:
        InputError: An asset class that is unknown and whose capabilities name no generic
            class, or a constraint its capabilities lack.
    """
    role = ROLE_CLASSES.get(desc.role_class)
    if role is None:
        raise InputError(
            f"{desc.asset_id}: unknown asset class {desc.asset_class!r}; "
            f"known: {sorted(ROLE_CLASSES)}"
        )
    g = Graph()
    g.bind("tt", TT)
    node = asset_iri(desc.asset_id)
    g.add((node, RDF.type, KIND_CLASSES[desc.kind]))
    g.add((node, RDF.type, role))
    g.add((node, TT.assetId, Literal(desc.asset_id)))
    g.add((node, TT.assetClass, Literal(desc.asset_class)))
    g.add((node, TT.status, Literal(status)))
    if state is not None:
        g.add((node, TT.operationalState, Literal(state)))
    if desc.physical_type is not None:
        g.add((node, TT.assetType, TYPE_IRIS[desc.physical_type]))
    for cap in desc.capabilities:
        g.add((node, TT.hasCapability, CAPABILITY_IRIS[cap]))
    for cap, spec in capability_specs(desc).items():
        for c in spec.constraints:
            bound = URIRef(f"{node}/capability/{cap.value}/{c.id_short}")
            g.add((node, TT.hasConstraint, bound))
            g.add((bound, RDF.type, TT.ConstraintValue))
            g.add((bound, TT.ofCapability, CAPABILITY_IRIS[cap]))
            g.add((bound, TT.constraint, TT[c.id_short]))
            g.add((bound, TT.value, Literal(c.initial)))
    if desc.station is not None:
        station = station_iri(desc.station)
        g.add((node, TT.atStation, station))
        g.add((station, RDF.type, TT.Station))
    if desc.models is not None:
        g.add((node, TT.virtualModelOf, asset_iri(desc.models)))
    if endpoint is not None:
        iface = interface_iri(desc.asset_id)
        g.add((node, TT.hasInterface, iface))
        g.add((node, TT.endpoint, Literal(endpoint)))
        g.add((iface, RDF.type, TT.Interface))
        g.add((iface, TT.endpointUrl, Literal(endpoint)))
        if security_policy is not None:
            g.add((iface, TT.securityPolicy, Literal(security_policy)))
    return g


@functools.cache
def _ontology_text() -> str:
    return resources.files("transfertwin.data").joinpath("ontology", "transfertwin.ttl").read_text()


def load_ontology() -> Graph:
    """A fresh graph holding the transfertwin ontology (classes, properties, individuals)."""
    return Graph().parse(data=_ontology_text(), format="turtle")
