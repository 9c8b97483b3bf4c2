"""The floor CA: issuing from a signing request, revoking through a signed CRL, and a trust
folder holding only the CA and its CRL (`TrustList`)."""

from __future__ import annotations

import asyncio
from datetime import UTC, datetime, timedelta
from pathlib import Path

import pytest
from asyncua import ua
from asyncua.common.utils import ServiceError
from cryptography import x509
from cryptography.hazmat.primitives.serialization import Encoding

from transfertwin.cps.opcua import (
    BACKDATE,
    TrustList,
    application_uri,
    certificate_uris,
    init_ca,
    install_certificate,
    load_ca,
    new_request,
)

_S = ua.StatusCodes


@pytest.fixture(scope="module")
def floor(tmp_path_factory: pytest.TempPathFactory):
    """A CA, one asset's certificate issued from its own request, a trust folder."""
    root = tmp_path_factory.mktemp("ca")
    ca = init_ca(root / "ca")
    cert = ca.issue(new_request(root / "tu", "TU_A", "127.0.0.2"))
    install_certificate(root / "tu", "TU_A", cert)
    return root, ca, cert


def test_issued_certificate_names_the_asset_and_is_backdated(floor) -> None:
    root, ca, cert = floor
    assert certificate_uris(cert) == [application_uri("TU_A")]
    assert cert.issuer == ca.cert.subject
    age = datetime.now(UTC) - cert.not_valid_before_utc
    assert BACKDATE - timedelta(seconds=5) <= age <= BACKDATE + timedelta(seconds=60)
    assert (root / "tu" / "TU_A.der").read_bytes() == cert.public_bytes(Encoding.DER)
    assert not (root / "tu" / "TU_A.csr.pem").exists()  # the request is used up
    assert (root / "tu" / "TU_A.pem").stat().st_mode & 0o077 == 0
    assert [r.name for r in load_ca(root / "ca").issued()] == ["TU_A"]


def test_trust_folder_of_ca_and_crl_trusts_what_the_ca_signed(floor, tmp_path: Path) -> None:
    _root, ca, cert = floor
    ca.install(tmp_path)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["ca.der", "crl.der"]
    trust = TrustList(tmp_path)
    assert trust.refusal(cert) is None
    other = init_ca(tmp_path / "other").issue(new_request(tmp_path / "x", "TU_A"))
    assert trust.refusal(other) == _S.BadCertificateUntrusted  # an untrusted CA's


def test_revoked_certificate_is_refused_once_the_crl_is_installed(tmp_path: Path) -> None:
    ca = init_ca(tmp_path / "ca")
    cert = ca.issue(new_request(tmp_path / "m", "TM_1"))
    ca.install(tmp_path / "trusted")
    trust = TrustList(tmp_path / "trusted")
    assert trust.refusal(cert) is None
    assert ca.revoke("TM_1") == [cert.serial_number]
    assert ca.revoke("TM_1") == []  # nothing left
    assert trust.refusal(cert) is None  # the asset's copy of the CRL is not yet the new one
    ca.install(tmp_path / "trusted")
    assert trust.refusal(cert) == _S.BadCertificateRevoked
    with pytest.raises(ServiceError) as err:
        asyncio.run(trust(cert, None))  # the server's validator at CreateSession
    assert err.value.code == _S.BadCertificateRevoked


def test_crl_not_signed_by_the_ca_is_ignored_and_the_last_verified_kept(tmp_path: Path) -> None:
    ca = init_ca(tmp_path / "ca")
    cert = ca.issue(new_request(tmp_path / "m", "TM_1"))
    ca.revoke("TM_1")
    ca.install(tmp_path / "trusted")
    trust = TrustList(tmp_path / "trusted")
    assert trust.refusal(cert) == _S.BadCertificateRevoked
    # a CRL of another CA with the same name, revoking nothing: its signature fails
    forged = init_ca(tmp_path / "forger", name="transfertwin floor CA")
    (tmp_path / "trusted" / "crl.der").write_bytes((tmp_path / "forger" / "crl.der").read_bytes())
    assert trust.refusal(cert) == _S.BadCertificateRevoked
    assert forged.cert.subject == ca.cert.subject


def test_expired_and_not_yet_valid_certificates_are_refused(tmp_path: Path) -> None:
    ca = init_ca(tmp_path / "ca")
    ca.install(tmp_path / "trusted")
    now = datetime.now(UTC)
    old = ca.issue(new_request(tmp_path / "a", "A"), not_before=now - timedelta(days=2),
                   not_after=now - timedelta(days=1))  # fmt: skip
    soon = ca.issue(new_request(tmp_path / "b", "B"), not_before=now + timedelta(days=1))
    trust = TrustList(tmp_path / "trusted")
    assert trust.refusal(old) == _S.BadCertificateTimeInvalid
    assert trust.refusal(soon) == _S.BadCertificateTimeInvalid


def test_server_validator_checks_the_uri_of_the_server_meant(floor, tmp_path: Path) -> None:
    _root, ca, cert = floor
    ca.install(tmp_path)
    trust = TrustList(tmp_path)
    app = ua.ApplicationDescription(ApplicationUri=application_uri("TU_A"),
                                    ApplicationType=ua.ApplicationType.Server)  # fmt: skip
    asyncio.run(trust.server_validator(application_uri("TU_A"))(cert, app))
    with pytest.raises(ServiceError) as err:
        asyncio.run(trust.server_validator(application_uri("TMS"))(cert, app))
    assert err.value.code == _S.BadCertificateUriInvalid


def test_request_without_a_transfertwin_uri_is_not_issued(tmp_path: Path) -> None:
    from cryptography.hazmat.primitives import hashes
    from cryptography.hazmat.primitives.asymmetric import rsa
    from cryptography.x509.oid import NameOID

    ca = init_ca(tmp_path / "ca")
    key = rsa.generate_private_key(public_exponent=65537, key_size=2048)
    csr = (x509.CertificateSigningRequestBuilder()
           .subject_name(x509.Name([x509.NameAttribute(NameOID.COMMON_NAME, "x")]))
           .sign(key, hashes.SHA256()))  # fmt: skip
    with pytest.raises(ValueError, match="no application URI"):
        ca.issue(csr)
    with pytest.raises(ValueError, match="already holds a CA"):
        init_ca(tmp_path / "ca")
