"""The composition root of a floor's assets: a node with the registry's roles
(`asset_node`), and the preparation of a process that forks asset processes
(`prepare_forking`)."""

from __future__ import annotations

import gc

from transfertwin.cps.floor import AssetConfig, FloorSpec
from transfertwin.cps.node import AssetNode
from transfertwin.cps.opcua import build_standard_address_space
from transfertwin.cps.roles import role_for

__all__ = ["asset_node", "prepare_forking"]


def asset_node(cfg: AssetConfig, floor: FloorSpec | None = None) -> AssetNode:
    """The node of the asset `cfg` describes, its role made by the registry (`role_for`).

    Args:
        cfg: The asset's configuration file, parsed.
        floor: The floor (None: read ``cfg.floor_file``).
    """
    return AssetNode(cfg, role_for, floor)


def prepare_forking() -> None:
    """Make this process the parent of asset processes forked from it: import what every
    asset needs (the node, the roles of units, objects and the graph; not the simulation,
    which only a module imports), build the OPC UA standard address space's template, and
    move all of it out of the collector's reach (`gc.freeze`), so that the forked processes
    share those pages copy-on-write instead of each building its own (about 60 of the
    90 MB of an object's process). Must run before any event loop or thread starts."""
    from transfertwin.cps.roles import GraphRole, ObjectRole, UnitRole

    del GraphRole, ObjectRole, UnitRole  # imported for the children
    build_standard_address_space()
    gc.collect()
    gc.freeze()
