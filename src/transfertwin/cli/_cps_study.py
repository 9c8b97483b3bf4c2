"""`transfertwin cps study start|status|stop|resume`: studies run by a floor's Experiment
Manager (docs/architecture.md, "Studies through the Experiment Manager").

Exit codes: 0 done (``start --wait``: the study finished), 2 bad input or a refusal by the
Experiment Manager (one line on stderr), 3 the study failed (``--wait``), 130 interrupted
while following (the study goes on in the Experiment Manager).
"""

from __future__ import annotations

import argparse
import asyncio
import json
import sys
import time
from pathlib import Path

from transfertwin._errors import InputError
from transfertwin.cli._cps_client import load_info

__all__ = ["register"]

#: Exit code of `start --wait` when the study failed.
EXIT_FAILED = 3


def _floor(workdir: str) -> tuple[dict, object, str]:
    """cps.json, the client credentials and the Experiment Manager's endpoint."""
    info, creds = load_info(Path(workdir))
    ems = [a for a in info["assets"] if a.get("class") == "experiment_manager"]
    if not ems:
        raise InputError(f"{workdir}: the floor has no Experiment Manager (add \"EM\" to "
                         "'logical' in the floor file)")  # fmt: skip
    return info, creds, ems[0]["endpoint"]


def _call(workdir: str, op: str, *args: object, timeout_s: float = 30.0) -> dict:
    """Call `op` on the Experiment Manager; its JSON answer. A refusal is an InputError."""
    from asyncua import ua

    from transfertwin.cps.opcua import OperationRefused, connect

    info, creds, endpoint = _floor(workdir)
    aid = endpoint.rsplit("/", 1)[-1]

    async def call() -> str:
        async with connect(endpoint, aid, credentials=creds, role="operator",
                           cert_dir=Path(info["cert_dir"]), insecure=info["insecure"],
                           timeout_s=timeout_s) as em:  # fmt: skip
            return await em.call(op, *args)

    try:
        return json.loads(asyncio.run(call()))
    except OperationRefused as exc:
        raise InputError(f"the Experiment Manager refused: {exc.reason}") from None
    except (TimeoutError, ConnectionError, OSError) as exc:
        raise InputError(f"{workdir}: the Experiment Manager is not answering "
                         f"({type(exc).__name__}); is the floor up?") from None  # fmt: skip
    except ua.UaStatusCodeError as exc:
        raise InputError(f"the Experiment Manager answered {exc}") from None


def _eta(status: dict) -> str:
    eta = status.get("eta_s")
    return "-" if eta is None or eta < 0 else f"{eta:.0f} s"


def status_line(st: dict) -> str:
    """One line: state, plan, done/planned, rate, ETA, store."""
    if st.get("plan") is None:
        return f"study: {st['state']}" + (f" (store {st['store']})" if st.get("store") else "")
    rate = st.get("rate_per_s")
    line = (f"study {st['plan']}: {st['state']}, {st['done']}/{st['planned']} experiments "
            f"({st['fraction']:.0%}), {f'{rate:.2f} exp/s' if rate else '- exp/s'}, "
            f"ETA {_eta(st)}; store {st['store']}")  # fmt: skip
    return line + (f"; error: {st['error']}" if st.get("error") else "")


def _follow(workdir: str, first: dict) -> int:
    """Show the study's progress (rich) until it ends; its exit code."""
    from rich.console import Console

    from transfertwin.cli._progress import progress_bar

    console = Console(stderr=True)
    st = first
    try:
        with progress_bar(f"study {st['plan']}", console) as on_progress:
            while True:
                on_progress(int(st["done"]), int(st["planned"]))
                if st["state"] not in ("starting", "running", "stopping"):
                    break
                time.sleep(0.5)
                st = _call(workdir, "StudyStatus")
    except KeyboardInterrupt:
        print("not following any more; the study goes on ('transfertwin cps study stop' "
              "stops it)", file=sys.stderr)  # fmt: skip
        return 130
    print(status_line(st))
    return EXIT_FAILED if st["state"] == "failed" else 0


def cmd_start(args: argparse.Namespace) -> int:
    """Start (or resume) a study from a JSON plan file."""
    plan = Path(args.plan)
    try:
        text = plan.read_text()
    except OSError as exc:
        raise InputError(f"--plan {args.plan}: cannot read ({exc.strerror or exc})") from None
    try:
        json.loads(text)
    except json.JSONDecodeError as exc:
        raise InputError(f"--plan {args.plan}: not JSON ({exc})") from None
    store = str(Path(args.store).resolve()) if args.store else ""
    st = _call(args.workdir, "StartStudy", text, store, timeout_s=120.0)
    print(status_line(st), flush=True)
    return _follow(args.workdir, st) if args.wait else 0


def cmd_resume(args: argparse.Namespace) -> int:
    """Resume the last study (stopped, or failed on a passing fault)."""
    st = _call(args.workdir, "StartStudy", "", "", timeout_s=120.0)
    print(status_line(st), flush=True)
    return _follow(args.workdir, st) if args.wait else 0


def cmd_status(args: argparse.Namespace) -> int:
    """The last study's state, progress, rate, ETA and store."""
    st = _call(args.workdir, "StudyStatus")
    print(json.dumps(st, indent=1) if args.json else status_line(st))
    return 0


def cmd_stop(args: argparse.Namespace) -> int:
    """Stop the running study after the experiments in flight."""
    st = _call(args.workdir, "StopStudy", timeout_s=180.0)
    print(status_line(st) + ("; 'transfertwin cps study resume' continues it"
                             if st["state"] == "stopped" else ""))  # fmt: skip
    return 0


def register(csub: argparse._SubParsersAction) -> None:
    """Add `cps study start|status|stop|resume`."""
    study = csub.add_parser("study", help="studies run by the floor's Experiment Manager")
    ssub = study.add_subparsers(dest="study_command", required=True, parser_class=type(study))
    p = ssub.add_parser("start", help="start or resume a study from a JSON plan")
    p.add_argument("--workdir", required=True, help="the floor's work folder (cps up --floor)")
    p.add_argument("--plan", required=True,
                   help="plan.json: objects, states or theta_step, runs, seed, docking, leg, "
                        "executor (local|ray), workers, store (docs/architecture.md)")
    p.add_argument("--store", help="SQLite result store (default: the plan's 'store', else "
                                   "one in the Experiment Manager's state folder)")
    p.add_argument("--wait", action="store_true", help="follow the progress until it ends")
    p.set_defaults(func=cmd_start)
    p = ssub.add_parser("resume", help="resume the last study")
    p.add_argument("--workdir", required=True)
    p.add_argument("--wait", action="store_true", help="follow the progress until it ends")
    p.set_defaults(func=cmd_resume)
    p = ssub.add_parser("status", help="state, progress, rate, ETA and store of the study")
    p.add_argument("--workdir", required=True)
    p.add_argument("--json", action="store_true", help="the status as one JSON document")
    p.set_defaults(func=cmd_status)
    p = ssub.add_parser("stop", help="stop the study after the experiments in flight")
    p.add_argument("--workdir", required=True)
    p.set_defaults(func=cmd_stop)
