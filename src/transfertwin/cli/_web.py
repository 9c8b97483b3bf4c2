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
    config = WebConfig(
        cps=Path(args.cps) if args.cps else None,
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


def register(sub: argparse._SubParsersAction) -> None:
    """Add `web` to the CLI."""
    p = sub.add_parser("web", help="web console: live CPS, orders, study progress and results")
    p.add_argument("--cps", metavar="WORKDIR", help="work folder of a running 'cps up'")
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
