"""The role registry: which `Role` serves an asset of each class (and HAL kind). It sits
above every role and is handed to the node as its factory (`AssetNode(cfg, role_for)`).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from transfertwin.cps.aas import AssetKind
from transfertwin.cps.node import Role
from transfertwin.cps.roles._graph import GraphRole
from transfertwin.cps.roles._unit import ObjectRole, UnitRole

if TYPE_CHECKING:
    from transfertwin.cps.node import AssetNode

__all__ = ["role_for"]


def role_for(node: AssetNode) -> Role:
    """The role of the node's asset class: the generic class it runs as, its own if the code
    knows it, else the one its capabilities name (`AssetDescriptor.role_class`: a second
    make of transport module runs a module's role, a buffer station a unit's). The roles
    that carry the simulation, the study stack or the dispatcher are imported when a node
    of their class is made: a unit's or an object's process imports none of them
    (`prepare_forking` keeps their pages shared)."""
    cls = node.desc.role_class
    if node.desc.kind is AssetKind.PHYSICAL and cls == "transfer_unit":  # the plant's own
        from transfertwin.cps.roles._plant_unit import PlantUnitRole

        return PlantUnitRole(node)
    if cls == "transport_module":
        if node.cfg.hal.kind == "remote":  # on real hardware, behind its HAL gateway
            from transfertwin.cps.roles._remote_module import RemoteModuleRole

            return RemoteModuleRole(node)
        from transfertwin.cps.roles._module import ModuleRole

        return ModuleRole(node)
    if cls == "transport_module_system":
        from transfertwin.cps.roles._tms import TmsRole

        return TmsRole(node)
    if cls == "props":
        from transfertwin.cps.roles._props import PropsRole

        return PropsRole(node)
    if cls == "experiment_manager":
        from transfertwin.cps.roles._em import ExperimentRole

        return ExperimentRole(node)
    roles = {"transfer_unit": UnitRole, "object": ObjectRole, "knowledge_graph": GraphRole}
    return roles.get(cls, Role)(node)
