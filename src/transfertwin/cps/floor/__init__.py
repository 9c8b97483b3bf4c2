"""A floor as files: the floor file (its stations, modules, objects, logical assets and
operation policy; `FloorSpec`), each asset's own configuration file (`AssetConfig`), the
built-in demonstration floor (`default_floor_spec`) and the emulated plant's seed file.
"""

from typing import TYPE_CHECKING

from transfertwin._lazy import lazy_exports

if TYPE_CHECKING:
    from transfertwin.cps.floor._asset_config import (
        DOCKING_MODES,
        HAL_KINDS,
        PROVENANCE,
        AssetConfig,
        HalConfig,
        load_asset_config,
        write_asset_config,
    )
    from transfertwin.cps.floor._floor_file import (
        LOGICAL_ASSETS,
        POLICIES,
        SAMPLINGS,
        SENSORS,
        FloorSpec,
        ModuleSpec,
        OperationSpec,
        StationSpec,
        default_floor_spec,
    )
    from transfertwin.cps.floor._floor_io import floor_toml, load_floor, parse_floor
    from transfertwin.cps.floor._plant_secret import (
        PLANT_SEED_FILE,
        check_plant_seed,
        read_plant_kind,
        read_plant_off,
        read_plant_seed,
        write_plant_seed,
    )

__all__ = [
    "DOCKING_MODES",
    "HAL_KINDS",
    "LOGICAL_ASSETS",
    "PLANT_SEED_FILE",
    "POLICIES",
    "PROVENANCE",
    "SAMPLINGS",
    "SENSORS",
    "AssetConfig",
    "FloorSpec",
    "HalConfig",
    "ModuleSpec",
    "OperationSpec",
    "StationSpec",
    "check_plant_seed",
    "default_floor_spec",
    "floor_toml",
    "load_asset_config",
    "load_floor",
    "parse_floor",
    "read_plant_kind",
    "read_plant_off",
    "read_plant_seed",
    "write_asset_config",
    "write_plant_seed",
]

__getattr__, __dir__ = lazy_exports(__name__, __file__)
