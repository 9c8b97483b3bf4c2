"""The cyber-physical system at runtime (Ch. 3, Sec. 5.2–5.3): one asset node per asset of a
floor (`asset_node`: the node of `cps.node` with the role of its class from `cps.roles`),
each serving its AAS over OPC UA, the knowledge graph and the logical assets; a floor's
nodes started as processes (`prepare_floor`, `launch`) or in one event loop (`LocalFloor`),
optionally on an emulated plant with its physical units beside the virtual models.

Every name loads on first use (`transfertwin._lazy`): the simulation, the study stack and
rdflib/pySHACL are imported only by what needs them, not by a client command (`cps
status`, `cps order`) or the web console's gateway.
"""

from typing import TYPE_CHECKING

from transfertwin._lazy import lazy_exports

if TYPE_CHECKING:
    from transfertwin.cps._compose import asset_node, prepare_forking
    from transfertwin.cps._launcher import (
        asset_pids,
        bundle_config,
        check_workdir,
        launch,
        local_address,
        prepare_floor,
        start_asset,
        stop_floor,
        write_floor_info,
    )
    from transfertwin.cps._local import LocalFloor
    from transfertwin.cps._supervisor import Supervisor
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
    from transfertwin.cps.floor import (
        DOCKING_MODES,
        AssetConfig,
        FloorSpec,
        HalConfig,
        ModuleSpec,
        StationSpec,
        check_plant_seed,
        default_floor_spec,
        floor_toml,
        load_asset_config,
        load_floor,
        write_asset_config,
    )
    from transfertwin.cps.hal import GatewayHAL, gateway_trust_dir
    from transfertwin.cps.kg import KnowledgeGraph
    from transfertwin.cps.node import AssetNode, default_lease
    from transfertwin.cps.opcua import (
        AssetClient,
        AssetServer,
        Credentials,
        OpcUaUnitHAL,
        ServerConfig,
        connect,
        new_credentials,
    )
    from transfertwin.cps.roles import (
        PHYSICAL_RECORD_EXTRA,
        PLANT_LOG,
        RUN_TRANSFER,
        physical_record,
        plant_descriptors,
    )

__all__ = [
    "DOCKING_MODES",
    "PHYSICAL_RECORD_EXTRA",
    "PLANT_LOG",
    "RUN_TRANSFER",
    "TYPE_PROPERTIES",
    "AssetClient",
    "AssetConfig",
    "AssetDescriptor",
    "AssetKind",
    "AssetNode",
    "AssetRepresentation",
    "AssetServer",
    "Capability",
    "Credentials",
    "FloorSpec",
    "GatewayHAL",
    "HalConfig",
    "KnowledgeGraph",
    "Layer",
    "LocalFloor",
    "ModuleSpec",
    "OpcUaUnitHAL",
    "PhysicalType",
    "PoseGraph",
    "PoseObservation",
    "ServerConfig",
    "StationSpec",
    "Supervisor",
    "asset_node",
    "asset_pids",
    "build_representation",
    "bundle_config",
    "check_plant_seed",
    "check_workdir",
    "connect",
    "default_floor_spec",
    "default_lease",
    "demo_descriptors",
    "export_aas",
    "externally_synced",
    "floor_toml",
    "gateway_trust_dir",
    "launch",
    "load_asset_config",
    "load_floor",
    "local_address",
    "new_credentials",
    "physical_record",
    "physical_twin",
    "plant_descriptors",
    "prepare_floor",
    "prepare_forking",
    "read_export",
    "start_asset",
    "stop_floor",
    "validate_export",
    "wire_signature",
    "write_asset_config",
    "write_floor_info",
]

__getattr__, __dir__ = lazy_exports(__name__, __file__)
