"""`transfertwin cps supervise`: restart a floor's asset processes that die unasked
(`transfertwin.cps.Supervisor`), beside a floor of this host (`cps up`, detached or not)."""

from __future__ import annotations

import argparse
import signal
import time
from pathlib import Path

from transfertwin._errors import InputError

__all__ = ["cmd_supervise", "register"]

#: Seconds between two looks at the floor's pid files.
PERIOD_S = 1.0


def cmd_supervise(args: argparse.Namespace) -> int:
    """Watch the floor in ``--workdir``: restart each asset process that died unasked (its
    pid file left behind), at most ``--max-restarts`` times within ``--window`` s; one line
    per restart. Ends (exit 0) on SIGINT/SIGTERM or when no asset of the floor runs and none
    is to be restarted (the floor taken down)."""
    from transfertwin.cps import Supervisor, asset_pids

    wd = Path(args.workdir)
    if args.max_restarts < 1 or not args.window > 0:
        raise InputError(f"--max-restarts must be >= 1 and --window > 0, got "
                         f"{args.max_restarts} and {args.window:g}")  # fmt: skip
    if not (wd / "assets").is_dir():
        raise InputError(f"{wd}: not a floor's work folder (no assets/; start one with "
                         "'transfertwin cps up --workdir ...')")  # fmt: skip
    if not asset_pids(wd):
        raise InputError(f"{wd}: no asset of the floor runs (start it with 'transfertwin cps "
                         "up', then supervise it)")  # fmt: skip
    sup = Supervisor(wd, args.max_restarts, args.window)
    stop = {"set": False}

    def on_signal(signum: int, frame: object) -> None:
        stop["set"] = True

    for sig in (signal.SIGINT, signal.SIGTERM):
        signal.signal(sig, on_signal)
    print(f"supervising the floor in {wd}: {len(asset_pids(wd))} asset processes", flush=True)
    while not stop["set"]:
        for line in sup.tick():
            print(f"{time.strftime('%H:%M:%S')} {line}", flush=True)
        if not asset_pids(wd) and not set(sup.died()) - sup.given_up:
            print("floor down: no asset process of it runs any more", flush=True)
            break
        time.sleep(PERIOD_S)
    return 0


def register(csub: argparse._SubParsersAction) -> None:
    """Add `cps supervise`."""
    p = csub.add_parser("supervise", help="restart the floor's asset processes that die "
                                          "unasked (killed, crashed)")  # fmt: skip
    p.add_argument("--workdir", required=True, help="the floor's work folder (this host's)")
    p.add_argument("--max-restarts", type=int, default=5,
                   help="restarts of one asset within --window before it is left down "
                        "(default 5)")  # fmt: skip
    p.add_argument("--window", type=float, default=300.0,
                   help="seconds over which restarts are counted (default 300)")
    p.set_defaults(func=cmd_supervise)
