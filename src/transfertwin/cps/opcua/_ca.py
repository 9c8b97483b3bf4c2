"""A floor's certificate authority (OPC UA Part 12's pattern, X.509 with `cryptography`).

One CA per floor signs every asset's application certificate; every asset trusts the CA
certificate and its revocation list (CRL), not N certificates. The CA's folder::

    ca.der        the CA certificate (self-signed, basicConstraints CA, keyCertSign, cRLSign)
    ca.key.pem    its private key (mode 0600; never leaves the CA's host)
    crl.der       the CRL, signed by the CA, rewritten on every revocation
    issued.json   what was issued: asset id, serial, validity, revoked

The API (``transfertwin cps ca init|issue|revoke|list`` call it):

- `init_ca` (a new CA in a folder), `load_ca` (an existing one), `ensure_ca` (either);
- `new_request` (where the asset runs: its own RSA key, never copied, and a signing request
  naming ``urn:transfertwin:<id>``);
- `FloorCA.issue` (a signing request -> an application certificate: the request's subject
  and SAN, notBefore backdated by `BACKDATE`, the key usages OPC UA asks for, client and
  server authentication), `install_certificate` (put it beside the key);
- `FloorCA.revoke` (an asset's certificates onto the CRL), `FloorCA.issued` (the table);
- `FloorCA.install` (the CA certificate and CRL into an asset's trust folder: what
  `transfertwin.cps.opcua.TrustList` loads, chain and CRL checked, the CRL's signature
  verified against the CA, re-read when the files change).
"""

from __future__ import annotations

import json
import os
from collections.abc import Iterable
from dataclasses import dataclass
from datetime import UTC, datetime, timedelta
from pathlib import Path

from cryptography import x509
from cryptography.hazmat.primitives import hashes
from cryptography.hazmat.primitives.asymmetric import rsa
from cryptography.hazmat.primitives.serialization import (
    Encoding,
    NoEncryption,
    PrivateFormat,
    load_pem_private_key,
)
from cryptography.x509.oid import ExtendedKeyUsageOID, NameOID

from transfertwin._atomic import write_atomic, write_bytes_atomic

__all__ = [
    "BACKDATE",
    "CA_CERT",
    "CRL_FILE",
    "FloorCA",
    "IssuedCertificate",
    "application_uri",
    "ensure_ca",
    "init_ca",
    "install_certificate",
    "load_ca",
    "new_request",
    "request_name",
]

CA_CERT, CA_KEY, CRL_FILE, INDEX = "ca.der", "ca.key.pem", "crl.der", "issued.json"

#: How far notBefore lies before the signing time: a host whose clock is a little behind
#: the CA's still accepts a certificate issued just now.
BACKDATE = timedelta(minutes=10)

_URI_PREFIX = "urn:transfertwin:"


def application_uri(name: str) -> str:
    """The OPC UA application URI of an asset (or client) `name`: ``urn:transfertwin:<name>``."""
    return f"{_URI_PREFIX}{name}"


@dataclass(frozen=True)
class IssuedCertificate:
    """One row of the CA's table (`FloorCA.issued`)."""

    name: str
    serial: int
    not_before: datetime
    not_after: datetime
    revoked: bool


def _now() -> datetime:
    return datetime.now(UTC).replace(microsecond=0)


def _write_key(path: Path, key: rsa.RSAPrivateKey) -> None:
    pem = key.private_bytes(Encoding.PEM, PrivateFormat.TraditionalOpenSSL, NoEncryption())
    write_bytes_atomic(path, pem, mode=0o600)


def init_ca(folder: Path, name: str = "transfertwin floor CA", *, days: int = 3650) -> FloorCA:
    """Make a new CA in `folder` (created): key, self-signed CA certificate, empty CRL.

    Raises:
        ValueError: `folder` already holds a CA.
    """
    folder = Path(folder)
    if (folder / CA_CERT).exists():
        raise ValueError(f"{folder}: already holds a CA ({CA_CERT}); use it or choose another")
    folder.mkdir(parents=True, exist_ok=True)
    key = rsa.generate_private_key(public_exponent=65537, key_size=3072)
    subject = x509.Name([x509.NameAttribute(NameOID.ORGANIZATION_NAME, "transfertwin"),
                         x509.NameAttribute(NameOID.COMMON_NAME, name)])  # fmt: skip
    now = _now()
    ski = x509.SubjectKeyIdentifier.from_public_key(key.public_key())
    cert = (
        x509.CertificateBuilder().subject_name(subject).issuer_name(subject)
        .public_key(key.public_key()).serial_number(x509.random_serial_number())
        .not_valid_before(now - BACKDATE).not_valid_after(now + timedelta(days=days))
        .add_extension(x509.BasicConstraints(ca=True, path_length=0), critical=True)
        .add_extension(x509.KeyUsage(digital_signature=True, content_commitment=False,
                                     key_encipherment=False, data_encipherment=False,
                                     key_agreement=False, key_cert_sign=True, crl_sign=True,
                                     encipher_only=False, decipher_only=False), critical=True)
        .add_extension(ski, critical=False)
        .add_extension(x509.AuthorityKeyIdentifier.from_issuer_subject_key_identifier(ski),
                       critical=False)
        .sign(key, hashes.SHA256())
    )  # fmt: skip
    _write_key(folder / CA_KEY, key)
    write_bytes_atomic(folder / CA_CERT, cert.public_bytes(Encoding.DER))
    ca = FloorCA(folder, cert, key)
    ca._write_index([])
    ca.write_crl()
    return ca


def load_ca(folder: Path) -> FloorCA:
    """The CA in `folder` (`init_ca` made it).

    Raises:
        ValueError: No CA there, or its files are unreadable (one line naming the folder).
    """
    folder = Path(folder)
    try:
        cert = x509.load_der_x509_certificate((folder / CA_CERT).read_bytes())
        key = load_pem_private_key((folder / CA_KEY).read_bytes(), password=None)
    except FileNotFoundError:
        raise ValueError(f"{folder}: no floor CA there (no {CA_CERT} and {CA_KEY}); make one "
                         "with 'transfertwin cps ca init'") from None  # fmt: skip
    except (OSError, ValueError) as exc:
        raise ValueError(f"{folder}: the CA's files are not readable ({exc})") from None
    return FloorCA(folder, cert, key)


def ensure_ca(folder: Path, name: str = "transfertwin floor CA") -> FloorCA:
    """The CA in `folder`, made there first if there is none."""
    folder = Path(folder)
    return load_ca(folder) if (folder / CA_CERT).exists() else init_ca(folder, name)


def new_request(cert_dir: Path, name: str, host: str | None = None, *, key_size: int = 2048,
                write_request: bool = True) -> x509.CertificateSigningRequest:  # fmt: skip
    """Where the asset runs: a new private key ``cert_dir/<name>.pem`` (mode 0600) and a
    signing request ``cert_dir/<name>.csr.pem`` for ``urn:transfertwin:<name>`` (and
    `host`, an IP address or DNS name, in the SAN; the file only with `write_request`: a
    request signed at once needs none). The key never leaves `cert_dir`."""
    cert_dir = Path(cert_dir)
    cert_dir.mkdir(parents=True, exist_ok=True)
    key = rsa.generate_private_key(public_exponent=65537, key_size=key_size)
    _write_key(cert_dir / f"{name}.pem", key)
    alt: list[x509.GeneralName] = [x509.UniformResourceIdentifier(application_uri(name))]
    if host:
        alt.append(_host_name(host))
    csr = (
        x509.CertificateSigningRequestBuilder()
        .subject_name(x509.Name([x509.NameAttribute(NameOID.ORGANIZATION_NAME, "transfertwin"),
                                 x509.NameAttribute(NameOID.COMMON_NAME, name)]))
        .add_extension(x509.SubjectAlternativeName(alt), critical=False)
        .sign(key, hashes.SHA256())
    )  # fmt: skip
    if write_request:
        write_bytes_atomic(cert_dir / f"{name}.csr.pem", csr.public_bytes(Encoding.PEM))
    return csr


def _host_name(host: str) -> x509.GeneralName:
    import ipaddress

    try:
        return x509.IPAddress(ipaddress.ip_address(host))
    except ValueError:
        return x509.DNSName(host)


def install_certificate(cert_dir: Path, name: str, cert: x509.Certificate) -> Path:
    """Put an issued certificate beside its key as ``cert_dir/<name>.der``.

    Raises:
        ValueError: The certificate is not for the key ``cert_dir/<name>.pem``.
    """
    key_file = Path(cert_dir) / f"{name}.pem"
    # only its public half is compared: the RSA key's validation (~40 ms) is not needed
    key = load_pem_private_key(key_file.read_bytes(), password=None,
                               unsafe_skip_rsa_key_validation=True)  # fmt: skip
    if key.public_key().public_numbers() != cert.public_key().public_numbers():
        raise ValueError(f"{key_file}: the certificate is not for this key (another request?)")
    path = Path(cert_dir) / f"{name}.der"
    write_bytes_atomic(path, cert.public_bytes(Encoding.DER))
    (Path(cert_dir) / f"{name}.csr.pem").unlink(missing_ok=True)
    return path


class FloorCA:
    """A floor's CA, loaded (`load_ca`, `init_ca`): issues, revokes, writes the CRL."""

    def __init__(self, folder: Path, cert: x509.Certificate, key) -> None:
        self.folder = Path(folder)
        self.cert = cert
        self._key = key
        self._pending: list[dict] | None = None  # rows of an issue_many

    # -- the table of issued certificates ----------------------------------------------
    def _index(self) -> list[dict]:
        try:
            return json.loads((self.folder / INDEX).read_text())["issued"]
        except FileNotFoundError:
            return []

    def _write_index(self, rows: list[dict]) -> None:
        write_atomic(self.folder / INDEX, json.dumps({"issued": rows}, indent=1) + "\n")

    def issued(self) -> list[IssuedCertificate]:
        """Every certificate this CA issued, oldest first."""
        return [IssuedCertificate(r["name"], int(r["serial"]),
                                  datetime.fromisoformat(r["not_before"]),
                                  datetime.fromisoformat(r["not_after"]), bool(r["revoked"]))
                for r in self._index()]  # fmt: skip

    # -- issuing ------------------------------------------------------------------------
    def issue(self, csr: x509.CertificateSigningRequest, *, days: int = 365,
              not_before: datetime | None = None,
              not_after: datetime | None = None) -> x509.Certificate:  # fmt: skip
        """An application certificate for a signing request (`new_request` made it).

        The request must be signed by its key and name exactly one ``urn:transfertwin:``
        URI in its SAN; the certificate keeps the request's subject and SAN and is valid
        from `BACKDATE` before now (or `not_before`) for `days` (or until `not_after`).
        Recorded in ``issued.json``.

        Raises:
            ValueError: A request that is not signed by its key or names no (or several)
                transfertwin URIs.
        """
        if not csr.is_signature_valid:
            raise ValueError("the signing request's signature does not verify")
        try:
            san = csr.extensions.get_extension_for_class(x509.SubjectAlternativeName).value
        except x509.ExtensionNotFound:
            raise ValueError("the signing request names no application URI (no SAN)") from None
        uris = [u for u in san.get_values_for_type(x509.UniformResourceIdentifier)
                if u.startswith(_URI_PREFIX)]  # fmt: skip
        if len(uris) != 1:
            raise ValueError(f"the signing request must name one {_URI_PREFIX}<id> URI, "
                             f"names {len(uris)}")  # fmt: skip
        name = uris[0].removeprefix(_URI_PREFIX)
        start = not_before or _now() - BACKDATE
        end = not_after or _now() + timedelta(days=days)
        cert = (
            x509.CertificateBuilder().subject_name(csr.subject).issuer_name(self.cert.subject)
            .public_key(csr.public_key()).serial_number(x509.random_serial_number())
            .not_valid_before(start).not_valid_after(end)
            .add_extension(san, critical=False)
            .add_extension(x509.BasicConstraints(ca=False, path_length=None), critical=True)
            .add_extension(x509.KeyUsage(digital_signature=True, content_commitment=True,
                                         key_encipherment=True, data_encipherment=True,
                                         key_agreement=False, key_cert_sign=False,
                                         crl_sign=False, encipher_only=False,
                                         decipher_only=False), critical=True)
            .add_extension(x509.ExtendedKeyUsage([ExtendedKeyUsageOID.SERVER_AUTH,
                                                  ExtendedKeyUsageOID.CLIENT_AUTH]),
                           critical=False)
            .add_extension(x509.SubjectKeyIdentifier.from_public_key(csr.public_key()),
                           critical=False)
            .add_extension(x509.AuthorityKeyIdentifier.from_issuer_public_key(
                self.cert.public_key()), critical=False)
            .sign(self._key, hashes.SHA256())
        )  # fmt: skip
        self._record(cert, name, start, end)
        return cert

    def _record(self, cert: x509.Certificate, name: str, start: datetime,
                end: datetime) -> None:  # fmt: skip
        rows = self._pending if self._pending is not None else self._index()
        rows.append({"name": name, "serial": str(cert.serial_number),
                     "not_before": start.isoformat(), "not_after": end.isoformat(),
                     "revoked": False})  # fmt: skip
        if self._pending is None:
            self._write_index(rows)

    def issue_many(self, csrs: Iterable[x509.CertificateSigningRequest]) -> list[x509.Certificate]:
        """`issue` for each request, the table written once (a floor's preparation); the
        requests may arrive one by one (an iterator: each is signed as it comes)."""
        self._pending = self._index()
        try:
            out = [self.issue(csr) for csr in csrs]
            self._write_index(self._pending)
        finally:
            self._pending = None
        return out

    # -- revoking -----------------------------------------------------------------------
    def revoke(self, name: str) -> list[int]:
        """Put every current certificate of `name` on the CRL (rewritten, signed).

        Returns:
            The serials revoked now (empty: nothing of `name` left to revoke).
        """
        rows = self._index()
        serials = []
        for r in rows:
            if r["name"] == name and not r["revoked"]:
                r["revoked"] = True
                r["revoked_at"] = _now().isoformat()
                serials.append(int(r["serial"]))
        if serials:
            self._write_index(rows)
            self.write_crl()
        return serials

    def crl(self) -> x509.CertificateRevocationList:
        """The CRL as the table says now, signed by the CA (valid 10 years: the floor's
        assets re-read it when its file changes, not when it falls due)."""
        now = _now()
        builder = (x509.CertificateRevocationListBuilder().issuer_name(self.cert.subject)
                   .last_update(now - BACKDATE)
                   .next_update(now + timedelta(days=3650)))  # fmt: skip
        for r in self._index():
            if r["revoked"]:
                at = datetime.fromisoformat(r.get("revoked_at", r["not_before"]))
                builder = builder.add_revoked_certificate(
                    x509.RevokedCertificateBuilder().serial_number(int(r["serial"]))
                    .revocation_date(at).build())  # fmt: skip
        return builder.sign(self._key, hashes.SHA256())

    def write_crl(self) -> Path:
        """Write ``crl.der`` in the CA's folder."""
        path = self.folder / CRL_FILE
        write_bytes_atomic(path, self.crl().public_bytes(Encoding.DER))
        return path

    def install(self, trust_dir: Path) -> None:
        """Copy the CA certificate and its CRL into an asset's trust folder (created; a
        file already the same is left alone). Each copy replaces the old one whole (a
        reader sees one or the other) but is not synced: the CA's own files are, and
        installing again repairs a copy a crash lost (``cps up`` and ``cps ca revoke`` do)."""
        trust_dir = Path(trust_dir)
        trust_dir.mkdir(parents=True, exist_ok=True)
        for name in (CA_CERT, CRL_FILE):
            data = (self.folder / name).read_bytes()
            target = trust_dir / name
            try:
                if target.read_bytes() == data:
                    continue
            except OSError:
                pass
            tmp = trust_dir / f".{name}.{os.getpid()}.tmp"
            tmp.write_bytes(data)
            os.replace(tmp, target)


def request_name(csr: x509.CertificateSigningRequest) -> str:
    """The asset (or client) a signing request is for, from its URI ('' if none)."""
    try:
        san = csr.extensions.get_extension_for_class(x509.SubjectAlternativeName).value
    except x509.ExtensionNotFound:
        return ""
    uris = [u for u in san.get_values_for_type(x509.UniformResourceIdentifier)
            if u.startswith(_URI_PREFIX)]  # fmt: skip
    return uris[0].removeprefix(_URI_PREFIX) if uris else ""
