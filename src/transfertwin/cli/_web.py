"""`transfertwin web`: the web console (live CPS, orders, live transfer, study progress and
results, calibration)."""

from __future__ import annotations

import argparse
import logging
import sys
from pathlib import Path

__all__ = ["register"]


def cmd_web(args: argparse.Namespace) -> int:
    """Serve the console until Ctrl-C."""
    from transfertwin._errors import InputError
    from transfertwin.store import SQLITE_SUFFIXES
    from transfertwin.web import WebConfig, serve

    for db in args.db or []:
        if Path(db).suffix.lower() not in SQLITE_SUFFIXES:
            raise InputError(f"--db {db}: a study store ({', '.join(SQLITE_SUFFIXES)})")
    if args.graph is not None and args.cps is not None:
        raise InputError("--cps (a floor's work folder) or --graph (a floor elsewhere): "
                         "choose one")  # fmt: skip
    cps = _remote_console(args) if args.graph is not None else args.cps
    config = WebConfig(
        cps=Path(cps) if cps else None,
        dbs=tuple(Path(db) for db in args.db or []),
        calibrations=tuple(Path(d) for d in args.calibration or []),
        host=args.host,
        port=args.port,
        token=args.token,
    )
    handler = logging.StreamHandler(sys.stderr)
    handler.setFormatter(logging.Formatter("%(asctime)s %(name)s: %(message)s"))
    audit = logging.getLogger("transfertwin.web.audit")
    audit.addHandler(handler)
    audit.setLevel(logging.INFO)
    if config.cps is not None:
        trail = logging.FileHandler(config.cps / "web-audit.log")
        trail.setFormatter(logging.Formatter("%(asctime)s %(message)s"))
        audit.addHandler(trail)

    def ready(url: str) -> None:
        print(f"console: {url}", flush=True)

    serve(config, on_ready=ready)
    print("console down", flush=True)
    return 0


def _remote_console(args: argparse.Namespace) -> Path:
    """The console's folder for a floor reached from another host (``--graph``, ``--ca``,
    ``--credential``): a ``cps.json`` as a floor's work folder has it, with the graph's
    endpoint (the console learns the other assets from its ``Status``), this process's
    client folder (the credential's certificate and key, the CA) and the credential's
    users, reading with the operator role it holds; the console's orders list and audit
    trail go there too. Removed at exit."""
    import atexit
    import json
    import shutil
    import tempfile

    from transfertwin._errors import InputError
    from transfertwin.cli._cps_client import remote_info

    if args.ca is None or args.credential is None:
        raise InputError("--graph needs --ca (the floor's CA certificate) and --credential "
                         "(an operator credential folder)")  # fmt: skip
    info, _ = remote_info(args.graph, args.ca, args.credential)
    folder = Path(tempfile.mkdtemp(prefix="transfertwin-console-"))
    atexit.register(shutil.rmtree, folder, True)
    policy = "Basic256Sha256_SignAndEncrypt"
    doc = {"floor": None, "assets": [{**a, "security_policy": policy} for a in info["assets"]],
           "credentials_file": str((Path(args.credential) / "credentials.json").resolve()),
           "cert_dir": info["cert_dir"], "insecure": False, "groups": [],
           "reader_role": "operator", "graph": args.graph}  # fmt: skip
    (folder / "cps.json").write_text(json.dumps(doc, indent=2) + "\n")
    return folder


def register(sub: argparse._SubParsersAction) -> None:
    """Add `web` to the CLI."""
    p = sub.add_parser("web", help="web console: live CPS, orders, study progress and results")
    p.add_argument("--cps", metavar="WORKDIR", help="work folder of a running 'cps up'")
    p.add_argument("--graph", metavar="URL",
                   help="a floor elsewhere: its knowledge graph's endpoint "
                        "(opc.tcp://HOST:PORT/transfertwin/KG), with --ca and --credential "
                        "as 'cps status --graph' takes them")  # fmt: skip
    p.add_argument("--ca", metavar="CA", help="with --graph: the floor's CA certificate (or a "
                   "folder with it and its CRL)")  # fmt: skip
    p.add_argument("--credential", metavar="DIR",
                   help="with --graph: an operator credential folder (client-operator.der, "
                        "client-operator.pem, credentials.json)")  # fmt: skip
    p.add_argument("--db", action="append", metavar="STUDY.sqlite",
                   help="study store to show (repeat for several)")  # fmt: skip
    p.add_argument("--calibration", action="append", metavar="DIR",
                   help="output folder of 'calibrate run' or 'calibrate evaluate' to show "
                   "(repeat for several)")  # fmt: skip
    p.add_argument("--host", default="127.0.0.1",
                   help="interface to bind (default loopback; others need --token)")  # fmt: skip
    p.add_argument("--port", type=int, default=8765, help="TCP port (default 8765; 0: any)")
    p.add_argument("--token", help="secret for write actions (and for every request off "
                   "loopback); default: a random one, printed with the URL")  # fmt: skip
    p.set_defaults(func=cmd_web)
