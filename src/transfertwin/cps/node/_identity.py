"""Who a peer asset is at another asset's server: its application certificate, signed by
the floor's CA and naming ``urn:transfertwin:<id>``, presented as an X.509 identity token
(signed with its key), and the role that identity gets, by the asset's class
(docs/security.md, "Identities")."""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from types import MappingProxyType

from transfertwin.cps.aas import AssetDescriptor

__all__ = ["PEER_ROLES", "peer_roles"]

#: The role of a peer asset's identity by its class. Every class calls operations of its
#: peers (each heartbeats the knowledge graph; the TMS orders the modules, a module the
#: units, the Experiment Manager the TMS), so each is an operator; a class left out here
#: gets no session as a peer at all.
PEER_ROLES: Mapping[str, str] = MappingProxyType({
    "knowledge_graph": "operator",
    "transport_module_system": "operator",
    "experiment_manager": "operator",
    "props": "operator",
    "transfer_unit": "operator",
    "transport_module": "operator",
    "object": "operator",
})  # fmt: skip


def peer_roles(descriptors: Iterable[AssetDescriptor]) -> tuple[tuple[str, str], ...]:
    """(asset id, role) of every asset of a floor whose class has a peer role."""
    return tuple(sorted((d.asset_id, PEER_ROLES[d.asset_class]) for d in descriptors
                        if d.asset_class in PEER_ROLES))  # fmt: skip
