"""The knowledge graph: ontology, SHACL validation and SPARQL queries (rdflib/pyshacl)."""

from transfertwin.cps.kg._describe import (
    ASSET_CLASSES,
    ASSET_NS,
    CAPABILITY_IRIS,
    KIND_CLASSES,
    ROLE_CLASSES,
    STATION_NS,
    TT,
    TYPE_IRIS,
    asset_iri,
    check_id,
    describe,
    load_ontology,
    station_iri,
)
from transfertwin.cps.kg._graph import ChangeKind, ChangeListener, KnowledgeGraph
from transfertwin.cps.kg._queries import (
    IDLE_TRANSPORT_MODULES,
    PREFIXES,
    RECEIVERS_AT,
    VIRTUAL_MODELS_OF,
    prepared,
    read_only_select,
)
from transfertwin.cps.kg._validate import asset_node, first_violation, validate_description

__all__ = [
    "ASSET_CLASSES",
    "ASSET_NS",
    "CAPABILITY_IRIS",
    "IDLE_TRANSPORT_MODULES",
    "KIND_CLASSES",
    "PREFIXES",
    "RECEIVERS_AT",
    "ROLE_CLASSES",
    "STATION_NS",
    "TT",
    "TYPE_IRIS",
    "VIRTUAL_MODELS_OF",
    "ChangeKind",
    "ChangeListener",
    "KnowledgeGraph",
    "asset_iri",
    "asset_node",
    "check_id",
    "describe",
    "first_violation",
    "load_ontology",
    "prepared",
    "read_only_select",
    "station_iri",
    "validate_description",
]
