"""What every `transfertwin cps` client command shares: where the floor is (its work folder
and cps.json on a one-host floor, or from any host the knowledge graph's endpoint, the
floor's CA and an operator credential: `floor_access`), the client credentials, one call on
an asset's server, and plain-text tables.

The `cps` command modules (`_cps`, `_cps_floor`, `_cps_ops`, `_cps_study`) import these
helpers from here and not from each other, so the commands form no circle.
"""

from __future__ import annotations

import argparse
import asyncio
import atexit
import json
import shutil
import tempfile
from collections.abc import Awaitable, Callable
from pathlib import Path
from typing import TypeVar

from transfertwin._errors import InputError
from transfertwin.cli._paths import out_dir

__all__ = ["add_access", "call_asset", "check_access", "endpoint_of", "floor_access",
           "load_info", "remote_info", "run_client", "text_table", "workdir_of"]  # fmt: skip

#: What an operator credential folder holds (`--credential`): the client's application
#: certificate and key, and the operator's user name and password.
CREDENTIAL_FILES = ("client-operator.der", "client-operator.pem", "credentials.json")

T = TypeVar("T")


def workdir_of(path: str, must_exist: bool) -> Path:
    """The CPS work folder `path`; with `must_exist`, one with a running CPS (its cps.json)."""
    if not must_exist:
        return out_dir(path)
    wd = Path(path)
    if not (wd / "cps.json").is_file():
        raise InputError(f"{path}: the CPS is not running (no cps.json); start it with "
                         "'transfertwin cps up'")  # fmt: skip
    return wd


def load_info(wd: Path) -> tuple[dict, object]:
    """The floor's cps.json and the client credentials it names (None when insecure)."""
    from transfertwin.cps.opcua import load_credentials

    path = wd / "cps.json"
    if not path.is_file():
        raise InputError(f"{wd}: no floor there (no cps.json); start one with "
                         "'transfertwin cps up --floor FLOOR --workdir DIR'")  # fmt: skip
    info = json.loads(path.read_text())
    creds = None if info.get("insecure") else load_credentials(Path(info["credentials_file"]))
    return info, creds


def endpoint_of(info: dict, asset_id: str) -> str:
    """The OPC UA endpoint of `asset_id` in cps.json (InputError if there is none)."""
    for a in info["assets"]:
        if a["id"] == asset_id:
            return a["endpoint"]
    raise InputError(f"no asset {asset_id!r} in the CPS")


async def call_asset(info: dict, creds, aid: str, op: str, *args, timeout_s: float = 10.0,
                     submodel: str = "ControlInterface", role: str = "operator"):  # fmt: skip
    """Call method `op` of asset `aid` as an operator (or `role`); its answer."""
    from transfertwin.cps.opcua import connect

    async with connect(endpoint_of(info, aid), aid, credentials=creds, role=role,
                       cert_dir=Path(info["cert_dir"]), insecure=info["insecure"],
                       timeout_s=timeout_s) as s:  # fmt: skip
        return await s.call(op, *args, submodel=submodel)


def add_access(p: argparse.ArgumentParser) -> None:
    """The options that say where a floor is: ``--workdir`` (a one-host floor's folder), or
    ``--graph`` with ``--ca`` and ``--credential`` (from any host)."""
    p.add_argument("--workdir", help="the floor's work folder (a floor on this host)")
    p.add_argument("--graph", metavar="URL",
                   help="the knowledge graph's endpoint, opc.tcp://HOST:PORT/transfertwin/KG: "
                        "operate a floor from any host (with --ca and --credential; no work "
                        "folder)")  # fmt: skip
    p.add_argument("--ca", metavar="CA",
                   help="with --graph: the floor's CA certificate (DER or PEM), or a folder "
                        "with it and its CRL (ca.der, crl.der): every server is checked "
                        "against it")  # fmt: skip
    p.add_argument("--credential", metavar="DIR",
                   help="with --graph: an operator credential, a folder with the client "
                        "certificate and key (client-operator.der, client-operator.pem) and "
                        "the user name and password (credentials.json)")  # fmt: skip


def floor_access(args: argparse.Namespace) -> tuple[str, dict, object]:
    """(where, the floor's description as cps.json has it, the client credentials) from
    ``--workdir``, or from ``--graph``/``--ca``/``--credential`` (the assets and their
    endpoints then come from the graph's ``Status``); InputError for a bad combination."""
    graph = check_access(args)
    if graph is None:
        wd = workdir_of(args.workdir, must_exist=True)
        return str(wd), *load_info(wd)
    return graph, *remote_info(graph, args.ca, args.credential)


def check_access(args: argparse.Namespace) -> str | None:
    """The ``--graph`` URL (None: ``--workdir``), after checking that the options say where
    the floor is in one way (InputError otherwise)."""
    graph = args.graph
    if (args.workdir is None) == (graph is None):
        raise InputError("give the floor's --workdir (this host), or --graph URL with --ca "
                         "and --credential (any host)")  # fmt: skip
    if graph is None and (args.ca is not None or args.credential is not None):
        raise InputError("--ca and --credential go with --graph (a floor on this host uses "
                         "its --workdir's)")  # fmt: skip
    return graph


def remote_info(graph: str, ca: str | None, credential: str | None) -> tuple[dict, object]:
    """The floor as its graph lists it, reached with the CA `ca` and the operator
    credential folder `credential`."""
    from transfertwin.cps.opcua import load_credentials

    if not graph.startswith("opc.tcp://") or not graph.rstrip("/").endswith("/KG"):
        raise InputError(f"--graph {graph}: not the knowledge graph's endpoint "
                         "(opc.tcp://HOST:PORT/transfertwin/KG)")  # fmt: skip
    if ca is None or credential is None:
        raise InputError("--graph needs --ca (the floor's CA certificate) and --credential "
                         "(an operator credential folder)")  # fmt: skip
    folder = Path(credential)
    missing = [f for f in CREDENTIAL_FILES if not (folder / f).is_file()]
    if missing:
        raise InputError(f"--credential {credential}: not an operator credential (no "
                         f"{', '.join(missing)}; it holds {', '.join(CREDENTIAL_FILES)})")
    try:
        creds = load_credentials(folder / "credentials.json")
        creds.for_role("operator")
    except (ValueError, KeyError, OSError) as exc:
        raise InputError(f"--credential {credential}: credentials.json holds no operator "
                         f"user ({type(exc).__name__})") from None
    info = {"assets": [{"id": "KG", "kind": "logical", "class": "knowledge_graph",
                        "endpoint": graph.rstrip("/"), "standby": False}],
            "cert_dir": str(_client_folder(folder, Path(ca))), "insecure": False,
            "graph": graph, "groups": None}  # fmt: skip
    from asyncua import ua

    try:
        status = json.loads(asyncio.run(call_asset(info, creds, "KG", "Status", timeout_s=10)))
    except BaseException as exc:
        shutil.rmtree(info["cert_dir"], ignore_errors=True)  # no floor here: nothing kept
        if isinstance(exc, OSError | TimeoutError | ConnectionError):
            raise InputError(f"--graph {graph}: the knowledge graph is not answering "
                             f"({type(exc).__name__})") from None
        if isinstance(exc, ua.UaError):  # not the floor's graph (its certificate), or refused us
            raise InputError(f"--graph {graph}: {exc}") from None
        raise
    info["assets"] += [{"id": a["id"], "kind": a["kind"], "class": a["class"],
                        "role_class": a.get("role_class", a["class"]),
                        "endpoint": a["address"], "standby": False}
                       for a in status["assets"] if a["id"] != "KG" and a.get("address")]
    return info, creds


def _client_folder(credential: Path, ca: Path) -> Path:
    """This process's client folder, as a floor's ``W/certs`` is laid out: the credential's
    certificate and key (links to them, nothing copied), and in ``trusted/`` the CA `ca`
    (a certificate file, written as ``ca.der``; or links to the files of a folder holding
    it and its CRL), against which every server is checked. Removed at exit."""
    from cryptography.hazmat.primitives.serialization import Encoding

    from transfertwin.cps.opcua import read_certificate

    if ca.is_dir():
        trusted = [p for p in sorted(ca.iterdir()) if p.is_file()]
        der = None
    else:
        trusted = []
        try:
            der = read_certificate(ca).public_bytes(Encoding.DER)
        except (ValueError, OSError) as exc:
            raise InputError(f"--ca {ca}: not a certificate ({exc})") from None
    folder = Path(tempfile.mkdtemp(prefix="transfertwin-client-"))
    atexit.register(shutil.rmtree, folder, True)
    for name in CREDENTIAL_FILES[:2]:
        (folder / name).symlink_to((credential / name).resolve())
    (folder / "trusted").mkdir()
    for path in trusted:
        (folder / "trusted" / path.name).symlink_to(path.resolve())
    if der is not None:
        (folder / "trusted" / "ca.der").write_bytes(der)
    return folder



def run_client(wd: Path, coro_fn: Callable[[], Awaitable[T]]) -> T:
    """Run a client coroutine; a CPS that does not answer, or a server that is not the
    asset meant (`UntrustedServer`), is reported in one line."""
    from asyncua import ua

    from transfertwin.cps.opcua import UntrustedServer

    try:
        return asyncio.run(coro_fn())
    except UntrustedServer as exc:
        raise InputError(f"{wd}: {exc}") from None
    except (TimeoutError, ConnectionError, OSError) as exc:
        raise InputError(
            f"{wd}: the CPS is not running or not answering "
            f"({type(exc).__name__}); start it with 'transfertwin cps up'"
        ) from None
    except ua.UaStatusCodeError as exc:
        if exc.code != ua.StatusCodes.BadCertificateUntrusted:
            raise
        raise InputError(
            f"{wd}: the CPS does not trust this client's certificate; trust it with "
            "'transfertwin cps trust CERT --workdir WORKDIR'"
        ) from None


def text_table(rows: list[dict], cols: tuple[str, ...]) -> str:
    """Plain columns, nothing truncated whatever the terminal width (the endpoint last)."""
    cells = [[str(r.get(c, "") or "") for c in cols] for r in rows]
    widths = [max([len(c), *(len(row[i]) for row in cells)]) for i, c in enumerate(cols)]
    lines = [cols, *cells]
    return "\n".join("  ".join(v.ljust(w) for v, w in zip(line, widths, strict=True)).rstrip()
                     for line in lines)  # fmt: skip
