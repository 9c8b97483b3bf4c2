"""Security of the asset servers: certificates, a trust list, demo users and roles.

Secure by default: Basic256Sha256 SignAndEncrypt with a self-signed application certificate
created on first start, username/password users with roles, no anonymous access. A *viewer*
may read, browse and subscribe; an *operator* may also write and call methods (order).
NoSecurity is only used when a caller passes ``insecure=True`` explicitly.

Trust list: a server accepts a session only from a client whose application certificate is
in its trust folder (one DER file per certificate, compared by SHA-256 of the whole
certificate, i.e. pinned). The folder is looked at again on every new session (its files'
stamps; a certificate is parsed again only when its file changed), so a certificate
added with `trust_certificate` (``transfertwin cps trust``) counts at once, without a
restart. It is checked twice: at CreateSession (an unknown certificate gets
BadCertificateUntrusted) and again by the user manager at ActivateSession (a client that
ignores the first refusal gets BadUserAccessDenied).
"""

from __future__ import annotations

import hashlib
import hmac
import json
import logging
import os
import secrets
import socket
from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from datetime import UTC, datetime
from pathlib import Path

from asyncua import ua
from asyncua.common.utils import ServiceError
from asyncua.crypto.cert_gen import setup_self_signed_certificate
from asyncua.crypto.permission_rules import PermissionRuleset, User, UserRole
from asyncua.crypto.uacrypto import check_certificate
from cryptography import x509
from cryptography.hazmat.primitives.asymmetric.types import PrivateKeyTypes
from cryptography.hazmat.primitives.serialization import Encoding, load_pem_private_key
from cryptography.x509.oid import ExtendedKeyUsageOID, NameOID

from transfertwin._atomic import file_stamp, write_atomic

__all__ = [
    "ROLES",
    "Credentials",
    "RoleRuleset",
    "RoleUserManager",
    "TrustList",
    "ensure_certificate",
    "free_port",
    "load_credentials",
    "new_credentials",
    "parsed_private_key",
    "read_certificate",
    "trust_certificate",
    "trust_certificates",
    "write_credentials",
]

log = logging.getLogger(__name__)

ROLES = ("viewer", "operator")

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
    """Viewers read; operators also write and call; nobody changes the address space."""

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
    """Username/password users mapped to roles; asyncua calls `get_user` on activation.

    Args:
        creds: The users.
        trust: If given, a session is refused unless the client's application certificate
            (the secure channel's peer certificate) is on this trust list.
    """

    def __init__(self, creds: Credentials, trust: TrustList | None = None) -> None:
        self._users = {u: (p, role) for role, (u, p) in creds.users.items()}
        self._trust = trust

    def get_user(self, iserver, username=None, password=None, certificate=None) -> User | None:
        """The user for these credentials, or None (refused)."""
        if self._trust is not None and not self._trust.is_trusted(certificate):
            return None
        if username is None or username not in self._users:
            return None
        expected, role = self._users[username]
        ok = hmac.compare_digest(
            hashlib.sha256(expected.encode()).digest(),
            hashlib.sha256((password or "").encode()).digest(),
        )
        return User(role=UserRole.User, name=role) if ok else None


def read_certificate(path: Path) -> x509.Certificate:
    """An X.509 certificate from a DER or PEM file.

    Raises:
        ValueError: Not a readable certificate (the message names the file).
    """
    try:
        data = Path(path).read_bytes()
    except OSError as exc:
        raise ValueError(f"{path}: cannot read the certificate ({exc.strerror})") from None
    for load in (x509.load_der_x509_certificate, x509.load_pem_x509_certificate):
        try:
            return load(data)
        except ValueError:
            continue
    raise ValueError(f"{path}: not an X.509 certificate (DER or PEM)")


def _fingerprint(der: bytes) -> str:
    return hashlib.sha256(der).hexdigest()


def trust_certificate(trust_dir: Path, cert: Path | x509.Certificate) -> Path:
    """Put a client certificate on a trust list (a DER copy named by CN and fingerprint).

    Args:
        trust_dir: The trust folder of the servers (created if missing).
        cert: The certificate or a DER/PEM file holding it.

    Returns:
        The file written (already there if the certificate was trusted before).

    Raises:
        ValueError: `cert` is not a readable certificate.
    """
    c = cert if isinstance(cert, x509.Certificate) else read_certificate(Path(cert))
    der = c.public_bytes(Encoding.DER)
    cn = c.subject.get_attributes_for_oid(NameOID.COMMON_NAME)
    stem = "".join(ch if ch.isalnum() or ch in "-_" else "_" for ch in
                   (str(cn[0].value) if cn else "cert"))[:40]  # fmt: skip
    trust_dir.mkdir(parents=True, exist_ok=True)
    path = trust_dir / f"{stem}-{_fingerprint(der)[:16]}.der"
    if not path.exists():
        write_atomic(path, der)
    return path


def trust_certificates(folders: Iterable[Path], certs: Sequence[Path | x509.Certificate]) -> int:
    """Put every one of `certs` on every trust list in `folders`, as `trust_certificate`
    does one by one, but each certificate is written (atomically, with its fsync) once, into
    the first folder, and hard-linked into the others; each folder's directory is synced
    once. The lists stay one per folder: a file removed from one folder revokes the
    certificate there only (files are replaced, never edited in place, so the links never
    change content). Where hard links are not possible (another file system), a copy.

    Returns:
        How many files were added (certificates already on a list count nothing).
    """
    folders = list(dict.fromkeys(Path(f) for f in folders))
    if not folders or not certs:
        return 0
    first = folders[0]
    had = set(os.listdir(first)) if first.is_dir() else set()
    sources = [trust_certificate(first, c) for c in certs]
    added = sum(p.name not in had for p in sources)
    for folder in folders[1:]:
        folder.mkdir(parents=True, exist_ok=True)
        present = set(os.listdir(folder))
        for src in sources:
            if src.name in present:
                continue
            try:  # the name appears with the whole, already synced content
                os.link(src, folder / src.name)
            except FileExistsError:
                continue
            except OSError:  # no hard links here
                write_atomic(folder / src.name, src.read_bytes())
            added += 1
        _sync_dir(folder)
    return added


def _sync_dir(folder: Path) -> None:
    """Make the entries of `folder` durable (its directory's fsync; not on Windows)."""
    try:
        fd = os.open(folder, os.O_RDONLY)
    except OSError:
        return
    try:
        os.fsync(fd)
    except OSError:
        pass
    finally:
        os.close(fd)


class TrustList:
    """The client certificates a server accepts: every DER/PEM file in `folder` (pinned).

    Usable as asyncua's certificate validator (called at CreateSession).
    """

    def __init__(self, folder: Path) -> None:
        self.folder = Path(folder)
        self._read: tuple[tuple, frozenset[str]] | None = None  # (the folder's stamps, ...)

    def fingerprints(self) -> frozenset[str]:
        """SHA-256 of every trusted certificate, as the folder holds them now: a file added,
        removed or rewritten counts at once; the certificates are parsed again only then
        (a floor's folder holds one per asset: 20 ms for 200, on every session)."""
        try:
            with os.scandir(self.folder) as entries:
                found = sorted((e.name, e.inode(), e.stat().st_size, e.stat().st_mtime_ns)
                               for e in entries
                               if e.name.lower().endswith((".der", ".pem")))  # fmt: skip
        except OSError:  # no folder: nothing trusted
            found = []
        stamps = tuple(found)
        if self._read is not None and self._read[0] == stamps:
            return self._read[1]
        out = set()
        for f in (self.folder / name for name, *_ in found):
            try:
                out.add(_fingerprint(read_certificate(f).public_bytes(Encoding.DER)))
            except (ValueError, OSError):
                log.warning("trust list: %s is not a certificate; ignored", f)
        self._read = (stamps, frozenset(out))
        return self._read[1]

    def is_trusted(self, der: bytes | None) -> bool:
        """Whether a DER certificate is on the list (None: no certificate, not trusted)."""
        return der is not None and _fingerprint(bytes(der)) in self.fingerprints()

    async def __call__(self, cert: x509.Certificate, app: ua.ApplicationDescription) -> None:
        """Refuse an untrusted or expired client certificate (asyncua validator)."""
        name = app.ApplicationUri if app is not None else "?"
        if not self.is_trusted(cert.public_bytes(Encoding.DER)):
            subject = cert.subject.rfc4514_string()
            log.warning("refused untrusted client certificate %s (%s); trust it with "
                        "'transfertwin cps trust'", subject, name)  # fmt: skip
            raise ServiceError(ua.StatusCodes.BadCertificateUntrusted)
        now = datetime.now(UTC)
        if not cert.not_valid_before_utc <= now <= cert.not_valid_after_utc:
            log.warning("refused expired client certificate %s (%s)", cert.subject, name)
            raise ServiceError(ua.StatusCodes.BadCertificateTimeInvalid)


async def ensure_certificate(
    cert_dir: Path, name: str, host: str = "127.0.0.1"
) -> tuple[Path, Path]:
    """(certificate, private key) of an application, created on first use."""
    cert_dir.mkdir(parents=True, exist_ok=True)
    cert, key = cert_dir / f"{name}.der", cert_dir / f"{name}.pem"
    uri = f"urn:transfertwin:{name}"
    if _usable(cert, key, uri, host):
        return cert, key
    await setup_self_signed_certificate(
        key, cert, uri, host,
        [ExtendedKeyUsageOID.CLIENT_AUTH, ExtendedKeyUsageOID.SERVER_AUTH],
        {"countryName": "DE", "organizationName": "transfertwin", "commonName": name},
    )  # fmt: skip
    os.chmod(key, 0o600)
    return cert, key


def _usable(cert: Path, key: Path, uri: str, host: str) -> bool:
    """Whether an existing certificate can be used as it is: both files there, the
    certificate current and naming `uri` and `host` (asyncua's checks). The private key is
    not parsed here (an RSA key's validation costs ~0.1 s, and every client connection
    asked for it twice: here and in asyncua's set_security, which loads it anyway)."""
    if not (cert.is_file() and key.is_file()):
        return False
    try:
        parsed = x509.load_der_x509_certificate(cert.read_bytes())
    except ValueError:  # not a certificate: made anew (asyncua would fail on it)
        cert.unlink()
        return False
    return not check_certificate(parsed, uri, host)


_KEYS: dict[tuple[str, tuple[int, int, int] | None], PrivateKeyTypes] = {}


def parsed_private_key(path: Path) -> PrivateKeyTypes:
    """The (unencrypted PEM) private key at `path`, parsed once per process while the file
    is unchanged. Parsing validates the RSA key (~40 ms); a CPS's servers start with their
    keys from `ensure_certificate`, and a test run or a restarted CPS starts them again."""
    ident = (str(path.resolve()), file_stamp(path))
    key = _KEYS.get(ident)
    if key is None:
        key = load_pem_private_key(path.read_bytes(), password=None)
        if len(_KEYS) >= 256:
            _KEYS.clear()
        _KEYS[ident] = key
    return key


def free_port(host: str = "127.0.0.1") -> int:
    """A TCP port free on `host` right now."""
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as s:
        s.bind((host, 0))
        return int(s.getsockname()[1])
