"""The cyber-physical runtime (Ch. 3, Sec. 5.2–5.3): assets, AAS virtual representations
served over OPC UA, the knowledge graph and the logical assets."""

from transfertwin.cps._aas import (
    AssetRepresentation,
    build_representation,
    externally_synced,
    wire_signature,
)
from transfertwin.cps._aas_demo import demo_descriptors, physical_twin
from transfertwin.cps._aas_export import export_aas, read_export, validate_export
from transfertwin.cps._assets import (
    TYPE_PROPERTIES,
    AssetDescriptor,
    AssetKind,
    Capability,
    Layer,
    PhysicalType,
)
from transfertwin.cps._client import AssetClient, connect
from transfertwin.cps._kg import KnowledgeGraph
from transfertwin.cps._props import PoseGraph, PoseObservation
from transfertwin.cps._remote_hal import OpcUaUnitHAL
from transfertwin.cps._runtime import Cps, CpsConfig
from transfertwin.cps._security import Credentials, new_credentials
from transfertwin.cps._server import AssetServer, ServerConfig

__all__ = [
    "TYPE_PROPERTIES",
    "AssetClient",
    "AssetDescriptor",
    "AssetKind",
    "AssetRepresentation",
    "AssetServer",
    "Capability",
    "Cps",
    "CpsConfig",
    "Credentials",
    "KnowledgeGraph",
    "Layer",
    "OpcUaUnitHAL",
    "PhysicalType",
    "PoseGraph",
    "PoseObservation",
    "ServerConfig",
    "build_representation",
    "connect",
    "demo_descriptors",
    "export_aas",
    "externally_synced",
    "new_credentials",
    "physical_twin",
    "read_export",
    "validate_export",
    "wire_signature",
]
