"""Who a peer asset is at another asset's server: its application certificate, signed by
the floor's CA and naming ``urn:transfertwin:<id>``, presented as an X.509 identity token
(signed with its key), and the role that identity gets, by the asset's class
(docs/security.md, "Identities")."""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from types import MappingProxyType

from transfertwin.cps.aas import AssetDescriptor
from transfertwin.cps.opcua import ASSET_ROLE

__all__ = ["PEER_ROLES", "peer_roles"]

#: The role of a peer asset's identity by its class. Every class calls operations of its
#: peers (each heartbeats the knowledge graph; the TMS orders the modules, a module the
#: units, the Experiment Manager the TMS), so each is an asset (`ASSET_ROLE`): an
#: operator's rights but the operator-only methods (`OPERATOR_METHODS`: Shutdown), so no
#: asset stops another; only people with the operator role do (`cps down`). A class left
#: out here gets no session as a peer at all.
PEER_ROLES: Mapping[str, str] = MappingProxyType({
    "knowledge_graph": ASSET_ROLE,
    "transport_module_system": ASSET_ROLE,
    "experiment_manager": ASSET_ROLE,
    "props": ASSET_ROLE,
    "transfer_unit": ASSET_ROLE,
    "transport_module": ASSET_ROLE,
    "object": ASSET_ROLE,
})  # fmt: skip


def peer_roles(descriptors: Iterable[AssetDescriptor]) -> tuple[tuple[str, str], ...]:
    """(asset id, role) of every asset of a floor whose class has a peer role (by the
    generic class it runs as: `AssetDescriptor.role_class`)."""
    return tuple(sorted((d.asset_id, PEER_ROLES[d.role_class]) for d in descriptors
                        if d.role_class in PEER_ROLES))  # fmt: skip
