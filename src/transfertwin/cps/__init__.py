"""The cyber-physical runtime (Ch. 3, Sec. 5.2–5.3): assets, AAS virtual representations
served over OPC UA, the knowledge graph and the logical assets; optionally an emulated plant
as the physical assets (`CpsConfig.plant_seed`).

The emulated plant's assets (`check_plant_seed`, `plant_descriptors`, ...), the runtime and
the applications (`Cps`, `CpsConfig`, `DOCKING_MODES`, `PoseGraph`,
`PoseObservation`) and the knowledge graph (`KnowledgeGraph`) load on first use: they bring
the simulation, the study stack and rdflib/pySHACL, which a client command (`cps status`,
`cps order`) or the web console's gateway does not need.
"""

from typing import TYPE_CHECKING

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
from transfertwin.cps.opcua import (
    AssetClient,
    AssetServer,
    Credentials,
    OpcUaUnitHAL,
    ServerConfig,
    connect,
    new_credentials,
)

if TYPE_CHECKING:
    from transfertwin.cps._asset_config import (
        AssetConfig,
        HalConfig,
        load_asset_config,
        write_asset_config,
    )
    from transfertwin.cps._floor_file import (
        FloorSpec,
        ModuleSpec,
        StationSpec,
        default_floor_spec,
        floor_toml,
        load_floor,
    )
    from transfertwin.cps._gateway import gateway_trust_dir
    from transfertwin.cps._hal import GatewayHAL
    from transfertwin.cps._launcher import (
        asset_pids,
        check_workdir,
        launch,
        prepare_floor,
        start_asset,
        stop_floor,
        write_floor_info,
    )
    from transfertwin.cps._lease import default_lease
    from transfertwin.cps._node import AssetNode, prepare_forking
    from transfertwin.cps._plant_assets import (
        PHYSICAL_RECORD_EXTRA,
        PLANT_LOG,
        RUN_TRANSFER,
        check_plant_seed,
        physical_record,
        plant_descriptors,
    )
    from transfertwin.cps._runtime import DOCKING_MODES, Cps, CpsConfig
    from transfertwin.cps.apps import PoseGraph, PoseObservation
    from transfertwin.cps.kg import KnowledgeGraph

_LAZY = {
    "AssetConfig": "_asset_config",
    "HalConfig": "_asset_config",
    "GatewayHAL": "_hal",
    "gateway_trust_dir": "_gateway",
    "load_asset_config": "_asset_config",
    "write_asset_config": "_asset_config",
    "FloorSpec": "_floor_file",
    "ModuleSpec": "_floor_file",
    "StationSpec": "_floor_file",
    "default_floor_spec": "_floor_file",
    "floor_toml": "_floor_file",
    "load_floor": "_floor_file",
    "default_lease": "_lease",
    "asset_pids": "_launcher",
    "check_workdir": "_launcher",
    "launch": "_launcher",
    "prepare_floor": "_launcher",
    "start_asset": "_launcher",
    "stop_floor": "_launcher",
    "write_floor_info": "_launcher",
    "AssetNode": "_node",
    "prepare_forking": "_node",
    "PHYSICAL_RECORD_EXTRA": "_plant_assets",
    "PLANT_LOG": "_plant_assets",
    "RUN_TRANSFER": "_plant_assets",
    "check_plant_seed": "_plant_assets",
    "physical_record": "_plant_assets",
    "plant_descriptors": "_plant_assets",
    "DOCKING_MODES": "_runtime",
    "Cps": "_runtime",
    "CpsConfig": "_runtime",
    "KnowledgeGraph": "kg",
    "PoseGraph": "apps",
    "PoseObservation": "apps",
}


def __getattr__(name: str) -> object:
    module = _LAZY.get(name)
    if module is None:
        raise AttributeError(f"module 'transfertwin.cps' has no attribute {name!r}")
    from importlib import import_module

    value = getattr(import_module(f"transfertwin.cps.{module}"), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(__all__))


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
    "Cps",
    "CpsConfig",
    "Credentials",
    "FloorSpec",
    "GatewayHAL",
    "HalConfig",
    "KnowledgeGraph",
    "Layer",
    "ModuleSpec",
    "OpcUaUnitHAL",
    "PhysicalType",
    "PoseGraph",
    "PoseObservation",
    "ServerConfig",
    "StationSpec",
    "asset_pids",
    "build_representation",
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
