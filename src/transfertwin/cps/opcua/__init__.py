"""OPC UA servers and clients built from the AAS, security and decentralised discovery."""

from transfertwin.cps.opcua._aspace import build_standard_address_space
from transfertwin.cps.opcua._client import AssetClient, connect
from transfertwin.cps.opcua._discovery import Discovery, Peer
from transfertwin.cps.opcua._remote_hal import OpcUaUnitHAL
from transfertwin.cps.opcua._security import (
    ROLES,
    Credentials,
    RoleRuleset,
    RoleUserManager,
    TrustList,
    ensure_certificate,
    free_port,
    load_credentials,
    new_credentials,
    read_certificate,
    trust_certificate,
    trust_certificates,
    write_credentials,
)
from transfertwin.cps.opcua._server import (
    NAMESPACE,
    AssetServer,
    Handler,
    OperationRefused,
    ServerConfig,
    node_id,
)

__all__ = [
    "NAMESPACE",
    "ROLES",
    "AssetClient",
    "AssetServer",
    "Credentials",
    "Discovery",
    "Handler",
    "OpcUaUnitHAL",
    "OperationRefused",
    "Peer",
    "RoleRuleset",
    "RoleUserManager",
    "ServerConfig",
    "TrustList",
    "build_standard_address_space",
    "connect",
    "ensure_certificate",
    "free_port",
    "load_credentials",
    "new_credentials",
    "node_id",
    "read_certificate",
    "trust_certificate",
    "trust_certificates",
    "write_credentials",
]
