"""The asset node: one asset's OPC UA server, its discovery, its lease at the knowledge
graph, its sessions to peers and its persisted state (`AssetNode`), and the `Role` protocol
through which the node runs what the asset does. The roles themselves are one layer up
(`transfertwin.cps.roles`): the node is handed a factory that makes them.
"""

from typing import TYPE_CHECKING

from transfertwin._lazy import lazy_exports

if TYPE_CHECKING:
    from transfertwin.cps.node._host import ModuleHost
    from transfertwin.cps.node._lease import (
        DEFAULT_LEASE_S,
        HEARTBEATS_PER_S,
        NO_LEASE,
        Renewal,
        default_lease,
        directory_reply,
        heartbeat_period,
        instance_id,
    )
    from transfertwin.cps.node._node import (
        LIFECYCLE,
        SHUTDOWN,
        AssetNode,
        RoleFactory,
        heartbeat_payload,
        lifecycle_submodel,
    )
    from transfertwin.cps.node._partners import (
        Partner,
        capability_name,
        find_partner_ids,
        find_partners,
        partners_from_rows,
        partners_query,
    )
    from transfertwin.cps.node._peers import Peers
    from transfertwin.cps.node._role import Role
    from transfertwin.cps.node._state import NodeState

__all__ = [
    "DEFAULT_LEASE_S",
    "HEARTBEATS_PER_S",
    "LIFECYCLE",
    "NO_LEASE",
    "SHUTDOWN",
    "AssetNode",
    "ModuleHost",
    "NodeState",
    "Partner",
    "Peers",
    "Renewal",
    "Role",
    "RoleFactory",
    "capability_name",
    "default_lease",
    "directory_reply",
    "find_partner_ids",
    "find_partners",
    "heartbeat_payload",
    "heartbeat_period",
    "instance_id",
    "lifecycle_submodel",
    "partners_from_rows",
    "partners_query",
]

__getattr__, __dir__ = lazy_exports(__name__, __file__)
