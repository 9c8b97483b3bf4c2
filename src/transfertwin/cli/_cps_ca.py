"""`transfertwin cps ca init|issue|revoke|list`: the floor's certificate authority
(docs/security.md, "Floor CA").

The CA lives in ``--ca DIR`` (default ``WORKDIR/ca``, where ``cps up`` makes it). An asset
on another host makes its own key and signing request there (its first start does, and
names the request); ``cps ca issue REQUEST`` signs it; the certificate goes back beside the
key. ``cps ca revoke ID`` puts the asset's certificates on the CRL and copies the CRL into
every trust folder of the work folder (an asset on another host needs the new ``crl.der``
in its trust folder; its peers refuse it as soon as theirs holds it).
"""

from __future__ import annotations

import argparse
from pathlib import Path

from transfertwin._errors import InputError

__all__ = ["register_ca"]


def _ca_dir(args: argparse.Namespace) -> Path:
    return Path(args.ca) if args.ca else Path(args.workdir or ".") / "ca"


def _load(args: argparse.Namespace):
    from transfertwin.cps.opcua import load_ca

    try:
        return load_ca(_ca_dir(args))
    except ValueError as exc:
        raise InputError(str(exc)) from None


def cmd_init(args: argparse.Namespace) -> int:
    """Make the floor's CA (refused where one is)."""
    from transfertwin.cps.opcua import init_ca

    try:
        ca = init_ca(_ca_dir(args), args.name)
    except ValueError as exc:
        raise InputError(str(exc)) from None
    print(
        f"floor CA {ca.cert.subject.rfc4514_string()} in {ca.folder} (its key "
        "ca.key.pem is the owner's only; trust folders take ca.der and crl.der)"
    )
    return 0


def _read_request(path: Path):
    from cryptography import x509

    try:
        data = path.read_bytes()
    except OSError as exc:
        raise InputError(f"{path}: cannot read the signing request ({exc.strerror})") from None
    for load in (x509.load_pem_x509_csr, x509.load_der_x509_csr):
        try:
            return load(data)
        except ValueError:
            continue
    raise InputError(f"{path}: not a certificate signing request (PEM or DER)")


def cmd_issue(args: argparse.Namespace) -> int:
    """Sign an asset's request: its certificate, written beside the request by default."""
    from cryptography.hazmat.primitives.serialization import Encoding

    if not 1 <= args.days <= 3650:
        raise InputError(f"--days must be 1..3650, got {args.days}")
    ca = _load(args)
    request = Path(args.request)
    csr = _read_request(request)
    try:
        cert = ca.issue(csr, days=args.days)
    except ValueError as exc:
        raise InputError(f"{request}: {exc}") from None
    stem = request.name.removesuffix(".pem").removesuffix(".der").removesuffix(".csr")
    out = Path(args.out) if args.out else request.with_name(f"{stem}.der")
    out.write_bytes(cert.public_bytes(Encoding.DER))
    start, end = cert.not_valid_before_utc, cert.not_valid_after_utc
    print(
        f"issued {cert.subject.rfc4514_string()} serial {cert.serial_number:x}, valid "
        f"{start:%Y-%m-%d %H:%M} to {end:%Y-%m-%d %H:%M} UTC: {out}"
    )
    return 0


def cmd_revoke(args: argparse.Namespace) -> int:
    """Revoke an asset's certificates; the CRL into every trust folder of the work folder."""
    ca = _load(args)
    serials = ca.revoke(args.asset)
    if not serials:
        raise InputError(f"no current certificate of {args.asset!r} in {ca.folder} (see "
                         "'transfertwin cps ca list')")  # fmt: skip
    wd = Path(args.workdir) if args.workdir else ca.folder.parent
    folders = [wd / "certs" / "trusted", *sorted((wd / "assets").glob("*/trusted"))]
    folders = [f for f in folders if (f / "ca.der").is_file()]
    for folder in folders:
        ca.install(folder)
    print(f"revoked {len(serials)} certificate(s) of {args.asset}; CRL {ca.folder / 'crl.der'} "
          f"copied into {len(folders)} trust folder(s) under {wd} (assets on other hosts need "
          "it in theirs)")  # fmt: skip
    return 0


def cmd_list(args: argparse.Namespace) -> int:
    """The certificates the CA issued."""
    rows = _load(args).issued()
    print(f"{'asset':<24} {'serial':<10} {'not before (UTC)':<17} {'not after (UTC)':<17} state")
    for r in rows:
        serial = f"{r.serial:x}"[:10]
        print(
            f"{r.name:<24} {serial:<10} {r.not_before:%Y-%m-%d %H:%M} "
            f"{r.not_after:%Y-%m-%d %H:%M} {'revoked' if r.revoked else 'valid'}"
        )
    return 0


def register_ca(csub: argparse._SubParsersAction) -> None:
    """Add `cps ca init|issue|revoke|list`."""
    ca = csub.add_parser("ca", help="the floor's certificate authority (init, issue, revoke, "
                                    "list)")  # fmt: skip
    sub = ca.add_subparsers(dest="ca_command", required=True, parser_class=type(ca))

    def common(p: argparse.ArgumentParser) -> None:
        p.add_argument("--ca", metavar="DIR", help="the CA's folder (default WORKDIR/ca)")
        p.add_argument("--workdir", help="the floor's work folder (default: .)")

    p = sub.add_parser("init", help="make the floor's CA (key, certificate, empty CRL)")
    common(p)
    p.add_argument("--name", default="transfertwin floor CA", help="the CA's common name")
    p.set_defaults(func=cmd_init)
    p = sub.add_parser("issue", help="sign an asset's certificate signing request")
    p.add_argument("request", metavar="REQUEST",
                   help="the request (PEM or DER) the asset made where it runs "
                        "(CERT_DIR/<id>.csr.pem)")  # fmt: skip
    common(p)
    p.add_argument("--out", metavar="CERT",
                   help="where to write the certificate (DER; default beside the request, "
                        "<id>.der)")  # fmt: skip
    p.add_argument("--days", type=int, default=365, help="validity in days (default 365)")
    p.set_defaults(func=cmd_issue)
    p = sub.add_parser("revoke", help="revoke an asset's certificates (its peers refuse it)")
    p.add_argument("asset", metavar="ID", help="the asset (or client-<role>)")
    common(p)
    p.set_defaults(func=cmd_revoke)
    p = sub.add_parser("list", help="the certificates the CA issued")
    common(p)
    p.set_defaults(func=cmd_list)
