"""Security of the asset servers: certificates, a trust list, demo users and roles.

Secure by default: Basic256Sha256 SignAndEncrypt with a self-signed application certificate
created on first start, username/password users with roles, no anonymous access. A *viewer*
may read, browse, subscribe and call the knowledge graph's read-only Query; an *operator*
may also write and call methods (order); a peer *asset* (its certificate as its identity)
may write and call methods too, except the `OPERATOR_METHODS` (Shutdown): peers cannot
stop each other, only the people operating the floor can.
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
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from datetime import UTC, datetime
from pathlib import Path

from asyncua import ua
from asyncua.common.utils import ServiceError
from asyncua.crypto.cert_gen import setup_self_signed_certificate
from asyncua.crypto.permission_rules import PermissionRuleset, User, UserRole
from asyncua.crypto.truststore import TrustStore
from asyncua.crypto.uacrypto import check_certificate
from asyncua.crypto.validator import CertificateValidator, CertificateValidatorOptions
from asyncua.ua.ua_binary import struct_from_binary
from cryptography import x509
from cryptography.hazmat.primitives.asymmetric.types import PrivateKeyTypes
from cryptography.hazmat.primitives.serialization import Encoding, load_pem_private_key
from cryptography.x509.oid import ExtendedKeyUsageOID, NameOID

from transfertwin._atomic import file_stamp, write_atomic
from transfertwin._errors import InputError

__all__ = [
    "ASSET_ROLE",
    "OPERATOR_METHODS",
    "ROLES",
    "Credentials",
    "PeerUser",
    "RoleRuleset",
    "RoleUserManager",
    "TrustList",
    "UserTable",
    "certificate_uris",
    "check_valid_now",
    "ensure_certificate",
    "free_port",
    "load_credentials",
    "load_users",
    "new_credentials",
    "parsed_private_key",
    "read_certificate",
    "trust_certificate",
    "trust_certificates",
    "write_credentials",
    "write_user_table",
]

log = logging.getLogger(__name__)

ROLES = ("viewer", "operator")

#: The role of a peer asset's certificate (an X.509 identity; by its class:
#: `transfertwin.cps.node.PEER_ROLES`): an operator's rights but the `OPERATOR_METHODS`.
ASSET_ROLE = "asset"

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


#: Methods a viewer may call too: they only read (the knowledge graph's SELECT-only Query).
VIEWER_METHODS = frozenset({"ControlInterface.Query"})

#: Methods only people with the operator role may call, never a peer asset's identity
#: (`ASSET_ROLE`): stopping an asset's process (`transfertwin.cps.node.SHUTDOWN`), and
#: steering the Experiment Manager's studies and calibration campaigns (no asset starts or
#: stops them; `cps study`, `cps campaign` do, with the operator's credential).
OPERATOR_METHODS = frozenset({
    "Lifecycle.Shutdown",
    "ControlInterface.StartStudy", "ControlInterface.StopStudy",
    "ControlInterface.StartCampaign", "ControlInterface.StopCampaign",
})  # fmt: skip


def _called_methods(body: object) -> list[str] | None:
    """``<submodel>.<operation>`` of every method a CallRequest's body (a binary buffer,
    read from a copy) calls; None when it is not a call body asyncua can read, or names a
    method by other than a string node id (neither is granted)."""
    try:
        params = struct_from_binary(ua.CallParameters, body.copy())  # type: ignore[attr-defined]
    except Exception:
        return None
    ids = [m.MethodId.Identifier for m in params.MethodsToCall or ()]
    if not all(isinstance(i, str) for i in ids):
        return None
    return [i.split(".", 1)[-1] for i in ids]


def _calls_only_viewer_methods(body: object) -> bool:
    """Whether a CallRequest's body calls `VIEWER_METHODS` and nothing else."""
    names = _called_methods(body)
    return bool(names) and all(n in VIEWER_METHODS for n in names)


def _calls_no_operator_method(body: object) -> bool:
    """Whether a CallRequest's body calls none of the `OPERATOR_METHODS`."""
    names = _called_methods(body)
    return names is not None and not any(n in OPERATOR_METHODS for n in names)


class RoleRuleset(PermissionRuleset):
    """Viewers read (and call `VIEWER_METHODS`); operators also write and call; peer
    assets (`ASSET_ROLE`) write and call all but the `OPERATOR_METHODS`; nobody changes
    the address space."""

    def __init__(self) -> None:
        self._read = {ua.NodeId(i) for i in _READ_TYPES}
        self._write = {ua.NodeId(i) for i in _WRITE_TYPES}
        self._call = ua.NodeId(ua.ObjectIds.CallRequest_Encoding_DefaultBinary)

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
        if action_type_id == self._call and user.name == "viewer":
            return _calls_only_viewer_methods(body)
        if action_type_id == self._call and user.name == ASSET_ROLE:
            return _calls_no_operator_method(body)
        return action_type_id in self._write and user.name in ("operator", ASSET_ROLE)


@dataclass
class PeerUser(User):
    """The user of a peer asset's session: its role, and the asset its certificate names
    (`transfertwin.cps.opcua.current_caller` tells a handler)."""

    asset_id: str = field(default="")


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


@dataclass(frozen=True)
class UserTable:
    """People's users as a server keeps them: user name -> (role, salt, scrypt hash of the
    password); no password in it. An asset's bundle holds this, not the passwords
    (`write_user_table`); the people's clear credentials stay with them."""

    users: dict[str, tuple[str, bytes, bytes]]

    @classmethod
    def of(cls, creds: Credentials) -> UserTable:
        """The table of `creds` (one salt per user; ~50 ms a user)."""
        table = {}
        for role, (name, password) in creds.users.items():
            salt = secrets.token_bytes(16)
            table[name] = (role, salt, _scrypt(password, salt))
        return cls(table)

    def role_of(self, username: str, password: str) -> str | None:
        """The user's role if `password` is theirs, else None."""
        entry = self.users.get(username)
        if entry is None:
            return None
        role, salt, digest = entry
        return role if hmac.compare_digest(_scrypt(password, salt), digest) else None


def _scrypt(password: str, salt: bytes) -> bytes:
    return hashlib.scrypt(password.encode(), salt=salt, n=2**14, r=8, p=1, dklen=32)


def write_user_table(path: Path, creds: Credentials) -> Path:
    """Write the servers' table of `creds` (`UserTable`: hashes, no password; mode 0600)."""
    table = UserTable.of(creds)
    data = {"users": {name: {"role": role, "salt": salt.hex(), "scrypt": digest.hex()}
                      for name, (role, salt, digest) in table.users.items()}}  # fmt: skip
    write_atomic(path, json.dumps(data, indent=2) + "\n", mode=0o600)
    return path


def load_users(path: Path) -> Credentials | UserTable:
    """What a server checks people against: a `UserTable` file (`write_user_table`) or,
    for a floor of one host or a test, a credentials file (`write_credentials`)."""
    data = json.loads(Path(path).read_text())
    if isinstance(data.get("users"), dict):
        return UserTable({name: (d["role"], bytes.fromhex(d["salt"]), bytes.fromhex(d["scrypt"]))
                          for name, d in data["users"].items()})  # fmt: skip
    return load_credentials(path)


class RoleUserManager:
    """Users mapped to roles; asyncua calls `get_user` on activation.

    Two kinds of user: a person (operator, viewer) by user name and password, and a peer
    asset by its application certificate (an X.509 identity token, signed with its key:
    asyncua checks that signature), the certificate trusted by `trust` (a CA's, not
    revoked, valid now) and naming ``urn:transfertwin:<id>`` of an asset in `peers`, which
    gives its role (by the asset's class: `transfertwin.cps.node.PEER_ROLES`).

    Args:
        creds: The people's users: their credentials, or only their `UserTable`.
        trust: If given, a session is refused unless the client's application certificate
            (the secure channel's peer certificate) is trusted by it; needed for peers.
        peers: Asset id -> the role its certificate gets (empty: no peer identities).
    """

    def __init__(self, creds: Credentials | UserTable, trust: TrustList | None = None,
                 peers: Mapping[str, str] | None = None) -> None:  # fmt: skip
        self._table = creds if isinstance(creds, UserTable) else None
        self._users = {} if self._table else {u: (p, r) for r, (u, p) in creds.users.items()}
        self._checked: dict[tuple[str, bytes], str] = {}  # (user, SHA-256 of a password) ok
        self._trust = trust
        self._peers = dict(peers or {})

    def get_user(self, iserver, username=None, password=None, certificate=None) -> User | None:
        """The user for these credentials, or None (refused). `certificate` is the X.509
        token's certificate for a peer, the channel's for a person."""
        if self._trust is not None and not self._trust.is_trusted(certificate):
            return None
        if username is None:
            return self._peer(certificate)
        if self._table is not None:
            role = self._table_role(username, password or "")
            return None if role is None else User(role=UserRole.User, name=role)
        if username not in self._users:
            return None
        expected, role = self._users[username]
        ok = hmac.compare_digest(
            hashlib.sha256(expected.encode()).digest(),
            hashlib.sha256((password or "").encode()).digest(),
        )
        return User(role=UserRole.User, name=role) if ok else None

    def _table_role(self, username: str, password: str) -> str | None:
        """The role by the table, a password once verified remembered by its SHA-256 (the
        console opens many sessions; scrypt costs ~50 ms each)."""
        key = (username, hashlib.sha256(password.encode()).digest())
        role = self._checked.get(key)
        if role is None:
            role = self._table.role_of(username, password)
            if role is not None:
                self._checked[key] = role
        return role

    def _peer(self, der: bytes | None) -> User | None:
        if der is None or self._trust is None:
            return None
        uris = certificate_uris(x509.load_der_x509_certificate(bytes(der)))
        ids = [u.removeprefix("urn:transfertwin:") for u in uris
               if u.startswith("urn:transfertwin:")]  # fmt: skip
        role = self._peers.get(ids[0]) if len(ids) == 1 else None
        if role is None:
            log.warning("refused X.509 identity %s: not an asset of this floor", uris)
            return None
        return PeerUser(role=UserRole.User, name=role, asset_id=ids[0])


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
    """The certificates a server (or client) accepts: every DER/PEM file in `folder`.

    A file may hold an application certificate, trusted as it is (pinned: compared by the
    SHA-256 of the whole certificate), a CA certificate (``ca.der``: every certificate it
    signed is trusted, chain checked by asyncua's `TrustStore`) or the CA's revocation list
    (``crl.der``: its signature is verified against the CA here, asyncua does not; a CRL
    that does not verify is ignored with an error in the log, and the revocations last
    verified stay in force). The folder is looked at again on every check (its files'
    stamps; parsed again only when one changed), so a certificate added, a CA replaced or
    a CRL rewritten counts at once, without a restart.

    Usable as asyncua's certificate validator of a server (called at CreateSession);
    `server_validator` makes a client's.
    """

    def __init__(self, folder: Path) -> None:
        self.folder = Path(folder)
        self._read: tuple[tuple, _Trust] | None = None  # (the folder's stamps, what it says)

    def _trust(self) -> _Trust:
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
        before = self._read[1] if self._read is not None else None
        trust = _Trust.read([self.folder / name for name, *_ in found], before)
        self._read = (stamps, trust)
        return trust

    def fingerprints(self) -> frozenset[str]:
        """SHA-256 of every pinned (non-CA) certificate, as the folder holds them now."""
        return self._trust().pinned

    def revoked(self) -> frozenset[int]:
        """The serials the folder's verified CRLs revoke, as they are now."""
        return self._trust().revoked

    def refusal(self, cert: x509.Certificate) -> int | None:
        """Why `cert` is not trusted (an OPC UA status code), None if it is: outside its
        validity (BadCertificateTimeInvalid), neither pinned nor signed by a CA here
        (BadCertificateUntrusted), or revoked (BadCertificateRevoked)."""
        now = datetime.now(UTC)
        if not cert.not_valid_before_utc <= now <= cert.not_valid_after_utc:
            return ua.StatusCodes.BadCertificateTimeInvalid
        trust = self._trust()
        if _fingerprint(cert.public_bytes(Encoding.DER)) in trust.pinned:
            return None
        if trust.store is None or not trust.signed(cert):
            return ua.StatusCodes.BadCertificateUntrusted
        if cert.serial_number in trust.revoked:
            return ua.StatusCodes.BadCertificateRevoked
        return None

    def is_trusted(self, der: bytes | None) -> bool:
        """Whether a DER certificate is trusted now (None: no certificate, not trusted)."""
        if der is None:
            return False
        try:
            cert = x509.load_der_x509_certificate(bytes(der))
        except ValueError:
            return False
        return self.refusal(cert) is None

    async def __call__(self, cert: x509.Certificate, app: ua.ApplicationDescription) -> None:
        """Refuse an untrusted, revoked or expired client certificate (asyncua validator)."""
        name = app.ApplicationUri if app is not None else "?"
        status = self.refusal(cert)
        if status is None:
            return
        subject = cert.subject.rfc4514_string()
        if status == ua.StatusCodes.BadCertificateUntrusted:
            log.warning("refused untrusted client certificate %s (%s); issue it from the "
                        "floor's CA ('transfertwin cps ca issue') or trust it with "
                        "'transfertwin cps trust'", subject, name)  # fmt: skip
        elif status == ua.StatusCodes.BadCertificateRevoked:
            log.warning("refused revoked client certificate %s (%s)", subject, name)
        else:
            log.warning("refused expired client certificate %s (%s)", subject, name)
        raise ServiceError(status)

    def server_validator(self, uri: str):
        """A client's check of the server it reached (asyncua's ``certificate_validator``):
        the certificate trusted here (`refusal`), its key usages those of a server
        (asyncua's `CertificateValidator`), and both its SAN and the server's description
        naming `uri`, the application the client meant to reach (else
        BadCertificateUriInvalid)."""
        usages = CertificateValidator(CertificateValidatorOptions.TIME_RANGE
                                      | CertificateValidatorOptions.KEY_USAGE
                                      | CertificateValidatorOptions.EXT_KEY_USAGE
                                      | CertificateValidatorOptions.PEER_SERVER)  # fmt: skip

        async def validate(cert: x509.Certificate, app: ua.ApplicationDescription) -> None:
            await usages.validate(cert, app)
            status = self.refusal(cert)
            if status is not None:
                log.warning("refused server %s: %s (%s)", uri,
                            ua.StatusCode(status).name, cert.subject.rfc4514_string())  # fmt: skip
                raise ServiceError(status)
            if uri not in certificate_uris(cert) or app.ApplicationUri != uri:
                log.warning("refused server: wanted %s, its certificate names %s", uri,
                            ", ".join(certificate_uris(cert)) or "no URI")  # fmt: skip
                raise ServiceError(ua.StatusCodes.BadCertificateUriInvalid)

        return validate


def certificate_uris(cert: x509.Certificate) -> list[str]:
    """The URIs in a certificate's subjectAltName (an OPC UA application's URI)."""
    try:
        san = cert.extensions.get_extension_for_class(x509.SubjectAlternativeName).value
    except x509.ExtensionNotFound:
        return []
    return list(san.get_values_for_type(x509.UniformResourceIdentifier))


@dataclass(frozen=True)
class _Trust:
    """What a trust folder says at one moment: pinned fingerprints, CA anchors (as
    asyncua's `TrustStore`) and the serials their verified CRLs revoke."""

    pinned: frozenset[str]
    store: TrustStore | None
    revoked: frozenset[int]
    crls: tuple[tuple[bytes, frozenset[int]], ...]  # (issuer DER, serials) verified

    def signed(self, cert: x509.Certificate) -> bool:
        """Whether `cert` chains to a CA here (asyncua's TrustStore, quietly: it logs a
        traceback for every certificate it refuses)."""
        quiet = logging.getLogger("asyncuagds.validate")
        level, quiet.level = quiet.level, logging.CRITICAL
        try:
            return self.store.is_trusted(cert)
        finally:
            quiet.level = level

    @classmethod
    def read(cls, files: list[Path], before: _Trust | None) -> _Trust:
        pinned, anchors, crls = set(), [], []
        for f in files:
            try:
                data = f.read_bytes()
            except OSError:
                continue
            crl = _load_crl(data)
            if crl is not None:
                crls.append((f, crl))
                continue
            try:
                cert = _load_cert(data)
            except ValueError:
                log.warning("trust list: %s is not a certificate or CRL; ignored", f)
                continue
            if _is_ca(cert):
                anchors.append(cert)
            else:
                pinned.add(_fingerprint(cert.public_bytes(Encoding.DER)))
        verified = dict(before.crls) if before is not None else {}
        for f, crl in crls:
            issuer = next((a for a in anchors if a.subject == crl.issuer), None)
            if issuer is None or not crl.is_signature_valid(issuer.public_key()):
                log.error("trust list: %s is not signed by a CA trusted here; ignored (the "
                          "revocations last verified stay in force)", f)  # fmt: skip
                continue
            verified[crl.issuer.public_bytes()] = frozenset(r.serial_number for r in crl)
        store = None
        if anchors:
            store = TrustStore([], [])
            store._trust_store = x509.verification.Store(anchors)  # what load_trust builds
        revoked = frozenset().union(*verified.values()) if verified else frozenset()
        return cls(frozenset(pinned), store, revoked, tuple(verified.items()))


def _load_cert(data: bytes) -> x509.Certificate:
    for load in (x509.load_der_x509_certificate, x509.load_pem_x509_certificate):
        try:
            return load(data)
        except ValueError:
            continue
    raise ValueError("not a certificate")


def _load_crl(data: bytes) -> x509.CertificateRevocationList | None:
    for load in (x509.load_der_x509_crl, x509.load_pem_x509_crl):
        try:
            return load(data)
        except ValueError:
            continue
    return None


def _is_ca(cert: x509.Certificate) -> bool:
    try:
        return cert.extensions.get_extension_for_class(x509.BasicConstraints).value.ca
    except x509.ExtensionNotFound:
        return False


async def ensure_certificate(
    cert_dir: Path, name: str, host: str = "127.0.0.1"
) -> tuple[Path, Path]:
    """(certificate, private key) of an application ``cert_dir/<name>.der`` and ``.pem``.

    A certificate a CA issued (issuer not its subject) is used as it is, never replaced
    here. Without one, a self-signed certificate is made on first use (and again when it
    expired or no longer names `name` and `host`): what a client or server outside a floor
    (a HAL gateway, a test) uses; a floor's CA does not trust it.

    Raises:
        InputError: The certificate is not valid yet (this host's clock is behind the
            issuer's) or has expired (a CA's: have a new one issued), or a signing request
            of this key waits for the CA (``<name>.csr.pem``, no certificate yet).
    """
    cert_dir.mkdir(parents=True, exist_ok=True)
    cert, key = cert_dir / f"{name}.der", cert_dir / f"{name}.pem"
    uri = f"urn:transfertwin:{name}"
    csr = cert_dir / f"{name}.csr.pem"
    if not cert.is_file() and key.is_file() and csr.is_file():
        raise InputError(f"{cert}: no certificate yet; have the signing request {csr} signed "
                         f"by the floor's CA ('transfertwin cps ca issue {csr} --ca CA_DIR "
                         f"--out {cert}')")  # fmt: skip
    if _usable(cert, key, uri, host):
        return cert, key
    await setup_self_signed_certificate(
        key, cert, uri, host,
        [ExtendedKeyUsageOID.CLIENT_AUTH, ExtendedKeyUsageOID.SERVER_AUTH],
        {"countryName": "DE", "organizationName": "transfertwin", "commonName": name},
    )  # fmt: skip
    os.chmod(key, 0o600)
    return cert, key


def check_valid_now(cert: x509.Certificate, where: Path | str) -> None:
    """InputError (one line naming `where`) unless `cert` is valid now: a certificate not
    valid yet means this host's clock is behind its issuer's; it is never replaced by a
    self-signed one."""
    now = datetime.now(UTC)
    fmt = "%Y-%m-%d %H:%M:%S UTC"
    if now < cert.not_valid_before_utc:
        raise InputError(f"{where}: certificate not valid before "
                         f"{cert.not_valid_before_utc.strftime(fmt)} and this host's clock "
                         f"says {now.strftime(fmt)}: set the clock (NTP)")  # fmt: skip
    if now > cert.not_valid_after_utc:
        raise InputError(f"{where}: certificate expired at "
                         f"{cert.not_valid_after_utc.strftime(fmt)}; have a new one issued "
                         "('transfertwin cps ca issue')")  # fmt: skip


def _usable(cert: Path, key: Path, uri: str, host: str) -> bool:
    """Whether an existing certificate can be used as it is: both files there and either
    issued by a CA and valid now (`check_valid_now` raises otherwise) or self-signed,
    current and naming `uri` and `host` (asyncua's checks; a self-signed one that is not
    valid yet is refused as a CA's is). The private key is not parsed here (an RSA key's
    validation costs ~0.1 s, and asyncua's set_security loads it anyway)."""
    if not (cert.is_file() and key.is_file()):
        return False
    try:
        parsed = x509.load_der_x509_certificate(cert.read_bytes())
    except ValueError:  # not a certificate: made anew (asyncua would fail on it)
        cert.unlink()
        return False
    if parsed.issuer != parsed.subject or datetime.now(UTC) < parsed.not_valid_before_utc:
        check_valid_now(parsed, cert)
        return True
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
