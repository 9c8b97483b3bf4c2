"""Security of the asset servers: certificates, demo users and role-based permissions.

Secure by default: Basic256Sha256 SignAndEncrypt with a self-signed application certificate
created on first start, username/password users with roles, no anonymous access. An
*observer* may read, browse and subscribe; an *operator* may also write and call methods.
NoSecurity is only used when a caller passes ``insecure=True`` explicitly.
"""

from __future__ import annotations

import hashlib
import hmac
import json
import os
import secrets
import socket
from dataclasses import dataclass
from pathlib import Path

from asyncua import ua
from asyncua.crypto.cert_gen import setup_self_signed_certificate
from asyncua.crypto.permission_rules import PermissionRuleset, User, UserRole
from cryptography.x509.oid import ExtendedKeyUsageOID

from transfertwin._atomic import write_atomic

__all__ = [
    "ROLES",
    "Credentials",
    "RoleRuleset",
    "RoleUserManager",
    "ensure_certificate",
    "free_port",
    "load_credentials",
    "new_credentials",
    "write_credentials",
]

ROLES = ("observer", "operator")

_READ_TYPES = {
    ua.ObjectIds.CreateSessionRequest_Encoding_DefaultBinary,
    ua.ObjectIds.CloseSessionRequest_Encoding_DefaultBinary,
    ua.ObjectIds.ActivateSessionRequest_Encoding_DefaultBinary,
    ua.ObjectIds.ReadRequest_Encoding_DefaultBinary,
    ua.ObjectIds.BrowseRequest_Encoding_DefaultBinary,
    ua.ObjectIds.BrowseNextRequest_Encoding_DefaultBinary,
    ua.ObjectIds.GetEndpointsRequest_Encoding_DefaultBinary,
    ua.ObjectIds.FindServersRequest_Encoding_DefaultBinary,
    ua.ObjectIds.TranslateBrowsePathsToNodeIdsRequest_Encoding_DefaultBinary,
    ua.ObjectIds.CreateSubscriptionRequest_Encoding_DefaultBinary,
    ua.ObjectIds.ModifySubscriptionRequest_Encoding_DefaultBinary,
    ua.ObjectIds.DeleteSubscriptionsRequest_Encoding_DefaultBinary,
    ua.ObjectIds.CreateMonitoredItemsRequest_Encoding_DefaultBinary,
    ua.ObjectIds.ModifyMonitoredItemsRequest_Encoding_DefaultBinary,
    ua.ObjectIds.DeleteMonitoredItemsRequest_Encoding_DefaultBinary,
    ua.ObjectIds.PublishRequest_Encoding_DefaultBinary,
    ua.ObjectIds.RepublishRequest_Encoding_DefaultBinary,
    ua.ObjectIds.CloseSecureChannelRequest_Encoding_DefaultBinary,
    ua.ObjectIds.SetMonitoringModeRequest_Encoding_DefaultBinary,
    ua.ObjectIds.SetPublishingModeRequest_Encoding_DefaultBinary,
    ua.ObjectIds.RegisterNodesRequest_Encoding_DefaultBinary,
    ua.ObjectIds.UnregisterNodesRequest_Encoding_DefaultBinary,
}
_WRITE_TYPES = {
    ua.ObjectIds.WriteRequest_Encoding_DefaultBinary,
    ua.ObjectIds.CallRequest_Encoding_DefaultBinary,
}


class RoleRuleset(PermissionRuleset):
    """Observers read; operators also write and call; nobody changes the address space."""

    def __init__(self) -> None:
        self._read = {ua.NodeId(i) for i in _READ_TYPES}
        self._write = {ua.NodeId(i) for i in _WRITE_TYPES}

    def check_validity(self, user: User, action_type_id: ua.NodeId, body: object) -> bool:
        """Whether `user` may send a request of type `action_type_id`."""
        if user is None or user.role is UserRole.Anonymous:
            return action_type_id in {
                ua.NodeId(ua.ObjectIds.CreateSessionRequest_Encoding_DefaultBinary),
                ua.NodeId(ua.ObjectIds.ActivateSessionRequest_Encoding_DefaultBinary),
                ua.NodeId(ua.ObjectIds.GetEndpointsRequest_Encoding_DefaultBinary),
                ua.NodeId(ua.ObjectIds.FindServersRequest_Encoding_DefaultBinary),
                # RegisterServer2 is a session-less discovery service: it arrives without a
                # user, protected only by the SignAndEncrypt secure channel.
                ua.NodeId(ua.ObjectIds.RegisterServer2Request_Encoding_DefaultBinary),
                ua.NodeId(ua.ObjectIds.CloseSessionRequest_Encoding_DefaultBinary),
                ua.NodeId(ua.ObjectIds.CloseSecureChannelRequest_Encoding_DefaultBinary),
            }
        if action_type_id in self._read:
            return True
        return action_type_id in self._write and user.name == "operator"


@dataclass(frozen=True)
class Credentials:
    """Username and password per role."""

    users: dict[str, tuple[str, str]]  # role -> (username, password)

    def for_role(self, role: str) -> tuple[str, str]:
        """(username, password) of a role."""
        return self.users[role]


def new_credentials() -> Credentials:
    """Fresh random demo users, one per role."""
    return Credentials(
        {role: (f"{role}-{secrets.token_hex(3)}", secrets.token_urlsafe(18)) for role in ROLES}
    )


def write_credentials(path: Path, creds: Credentials) -> Path:
    """Write credentials as JSON readable by the owner only (mode 0600)."""
    data = {role: {"username": u, "password": p} for role, (u, p) in creds.users.items()}
    write_atomic(path, json.dumps(data, indent=2) + "\n", mode=0o600)
    return path


def load_credentials(path: Path) -> Credentials:
    """Read a credentials file written by `write_credentials`."""
    data = json.loads(Path(path).read_text())
    return Credentials({r: (d["username"], d["password"]) for r, d in data.items()})


class RoleUserManager:
    """Username/password users mapped to roles; asyncua calls `get_user` on activation."""

    def __init__(self, creds: Credentials) -> None:
        self._users = {u: (p, role) for role, (u, p) in creds.users.items()}

    def get_user(self, iserver, username=None, password=None, certificate=None) -> User | None:
        """The user for these credentials, or None (refused)."""
        if username is None or username not in self._users:
            return None
        expected, role = self._users[username]
        ok = hmac.compare_digest(
            hashlib.sha256(expected.encode()).digest(),
            hashlib.sha256((password or "").encode()).digest(),
        )
        return User(role=UserRole.User, name=role) if ok else None


async def ensure_certificate(
    cert_dir: Path, name: str, host: str = "127.0.0.1"
) -> tuple[Path, Path]:
    """(certificate, private key) of an application, created on first use."""
    cert_dir.mkdir(parents=True, exist_ok=True)
    cert, key = cert_dir / f"{name}.der", cert_dir / f"{name}.pem"
    await setup_self_signed_certificate(
        key, cert, f"urn:transfertwin:{name}", host,
        [ExtendedKeyUsageOID.CLIENT_AUTH, ExtendedKeyUsageOID.SERVER_AUTH],
        {"countryName": "DE", "organizationName": "transfertwin", "commonName": name},
    )  # fmt: skip
    os.chmod(key, 0o600)
    return cert, key


def free_port(host: str = "127.0.0.1") -> int:
    """A TCP port free on `host` right now."""
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as s:
        s.bind((host, 0))
        return int(s.getsockname()[1])
