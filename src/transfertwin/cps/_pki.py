"""A floor's certificates from its CA (docs/security.md, "Floor CA").

`prepare_certificates` is what `cps up` does for a floor on one host: the CA in
``W/ca`` (made on the first start), one application certificate per asset, made as the
asset makes it where it runs (its own key and signing request in its certificate folder,
`new_request`) and signed by the CA, the command-line clients' certificates
(``W/certs/client-<role>``), and in every trust folder the CA certificate and its CRL only.
A certificate still current is kept; a revoked one too (a restart does not put a revoked
asset back on the floor: ``cps ca issue`` does).

Its cost is the RSA keys (2048 bits, the least Basic256Sha256 allows; ~50 ms of CPU each,
nine tenths of the whole): they are made in worker processes, one per core, and the main
process makes the CA's own key and signs each request as it comes back, so nothing waits for
the last key but that key's certificate (`benchmarks/cps_certificates.py`).
"""

from __future__ import annotations

import logging
import os
from collections.abc import Iterable, Iterator
from concurrent.futures import ProcessPoolExecutor
from contextlib import contextmanager
from datetime import UTC, datetime, timedelta
from pathlib import Path

from cryptography import x509

from transfertwin.cps.floor import AssetConfig
from transfertwin.cps.opcua import (
    CA_CERT,
    ROLES,
    FloorCA,
    application_uri,
    certificate_uris,
    init_ca,
    install_certificate,
    load_ca,
    new_request,
)

__all__ = ["CA_DIR", "prepare_certificates"]

log = logging.getLogger(__name__)

#: The CA's folder in a floor's work folder.
CA_DIR = "ca"

#: A certificate that expires sooner than this is issued anew at a start.
RENEW_BEFORE = timedelta(days=7)


def prepare_certificates(workdir: Path, configs: Iterable[AssetConfig]) -> FloorCA:
    """The floor's CA (``W/ca``, made if missing), a CA-signed certificate for every
    asset of `configs` (``cert_dir/<id>.der``, the key beside it) and for the command-line
    clients (``W/certs/client-<role>.der``), and the CA certificate and CRL in every trust
    folder (``W/certs/trusted`` and each asset's ``trust_dir``). Keys are made in parallel
    (one process per core) while this one makes the CA (the first time) and signs the
    requests as they come: a floor of 200 assets needs 200 RSA keys."""
    configs = list(configs)
    folder = Path(workdir) / CA_DIR
    wanted = [(Path(workdir) / "certs", f"client-{role}", None) for role in ROLES]
    wanted += [(cfg.cert_dir, cfg.asset_id, cfg.host) for cfg in configs]
    ca = load_ca(folder) if (folder / CA_CERT).exists() else None
    if ca is None:  # a new CA issued nothing yet: every certificate is made
        todo = wanted
    else:
        revoked = {r.serial for r in ca.issued() if r.revoked}
        todo = [w for w in wanted if not _current(ca, *w, revoked)]
    with _requests(todo) as requests:
        ca = ca or init_ca(folder)  # its key is made while the workers make theirs
        done: list[tuple[Path, str]] = []

        def arriving() -> Iterator[x509.CertificateSigningRequest]:
            for (folder_, name, _host), csr in requests:
                done.append((folder_, name))
                yield csr

        certs = ca.issue_many(arriving())
    for (cert_dir, name), cert in zip(done, certs, strict=True):
        install_certificate(cert_dir, name, cert)
    return _finish(ca, workdir, configs)


def _finish(ca: FloorCA, workdir: Path, configs: list[AssetConfig]) -> FloorCA:
    for folder in dict.fromkeys([Path(workdir) / "certs" / "trusted",
                                 *(cfg.trust_dir for cfg in configs)]):  # fmt: skip
        ca.install(folder)
    return ca


@contextmanager
def _requests(todo: list[tuple[Path, str, str | None]]):
    """An iterator of ((folder, name, host), signing request) for each of `todo`, in that
    order, as they are made; the keys are made in worker processes (one per core this
    process may use), which start at once, when there are many."""
    if len(todo) < 8:
        yield ((t, new_request(*t, write_request=False)) for t in todo)
        return
    cores = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count()
    with ProcessPoolExecutor(max_workers=cores or 1) as pool:
        pems = pool.map(_request, todo, chunksize=max(1, len(todo) // (8 * (cores or 1))))
        yield ((t, x509.load_pem_x509_csr(pem)) for t, pem in zip(todo, pems, strict=True))


def _request(item: tuple[Path, str, str | None]) -> bytes:
    from cryptography.hazmat.primitives.serialization import Encoding

    return new_request(*item, write_request=False).public_bytes(Encoding.PEM)


def _current(ca: FloorCA, folder: Path, name: str, host: str | None,
             revoked: set[int]) -> bool:  # fmt: skip
    """Whether ``folder/<name>.der`` is this CA's, for `name`, its key beside it, and valid
    for `RENEW_BEFORE` at least (or revoked: kept, see the module docstring). The address
    in its SAN is not compared: an asset keeps its certificate when its address changes
    (asyncua only warns about a host name missing there; the URI names the asset)."""
    cert_file, key_file = folder / f"{name}.der", folder / f"{name}.pem"
    if not (cert_file.is_file() and key_file.is_file()):
        return False
    try:
        cert = x509.load_der_x509_certificate(cert_file.read_bytes())
        cert.verify_directly_issued_by(ca.cert)
    except (ValueError, TypeError, x509.InvalidSignature):
        return False
    if cert.serial_number in revoked:
        log.warning("%s: certificate revoked; kept (issue a new one with 'transfertwin cps "
                    "ca issue')", name)  # fmt: skip
        return True
    if certificate_uris(cert) != [application_uri(name)]:
        return False
    return cert.not_valid_after_utc - datetime.now(UTC) > RENEW_BEFORE
