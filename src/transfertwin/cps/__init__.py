"""The cyber-physical runtime (Ch. 3, Sec. 5.2–5.3): assets, AAS virtual representations
served over OPC UA, the knowledge graph and the logical assets; optionally an emulated plant
as the physical assets (`CpsConfig.plant_seed`)."""

from transfertwin.cps._plant_assets import (
    PHYSICAL_RECORD_EXTRA,
    PLANT_LOG,
    RUN_TRANSFER,
    check_plant_seed,
    physical_record,
    plant_descriptors,
)
from transfertwin.cps._runtime import DOCKING_MODES, Cps, CpsConfig
from transfertwin.cps.aas import (
    TYPE_PROPERTIES,
    AssetDescriptor,
    AssetKind,
    AssetRepresentation,
    Capability,
    Layer,
    PhysicalType,
    build_representation,
    demo_descriptors,
    export_aas,
    externally_synced,
    physical_twin,
    read_export,
    validate_export,
    wire_signature,
)
from transfertwin.cps.apps import PoseGraph, PoseObservation
from transfertwin.cps.kg import KnowledgeGraph
from transfertwin.cps.opcua import (
    AssetClient,
    AssetServer,
    Credentials,
    OpcUaUnitHAL,
    ServerConfig,
    connect,
    new_credentials,
)

__all__ = [
    "DOCKING_MODES",
    "PHYSICAL_RECORD_EXTRA",
    "PLANT_LOG",
    "RUN_TRANSFER",
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
    "check_plant_seed",
    "connect",
    "demo_descriptors",
    "export_aas",
    "externally_synced",
    "new_credentials",
    "physical_record",
    "physical_twin",
    "plant_descriptors",
    "read_export",
    "validate_export",
    "wire_signature",
]
