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
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

from transfertwin._errors import InputError
from transfertwin.cli._cps_client import load_info

__all__ = ["register"]

#: Exit code of `start --wait` when the study failed.
EXIT_FAILED = 3


def _floor(workdir: str) -> tuple[dict, object, str]:
    """cps.json, the client credentials and the Experiment Manager's endpoint."""
    info, creds = load_info(Path(workdir))
    ems = [a for a in info["assets"]
           if a.get("role_class", a.get("class")) == "experiment_manager"]  # fmt: skip
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


@dataclass(frozen=True)
class Steering:
    """`resume`, `status` and `stop` of a job the Experiment Manager runs (a study, a
    campaign): its operations, how a status reads, how it is followed.

    Attributes:
        noun: 'study' or 'campaign' (the command's name).
        resume: The start operation and its arguments that resume the last job.
        status_op: The status operation.
        stop_op: The stop operation.
        line: One status as a line.
        follow: (workdir, first status) → exit code, following it until it ends.
    """

    noun: str
    resume: tuple[str, ...]
    status_op: str
    stop_op: str
    line: Callable[[dict], str]
    follow: Callable[[str, dict], int]

    def cmd_resume(self, args: argparse.Namespace) -> int:
        st = _call(args.workdir, *self.resume, timeout_s=120.0)
        print(self.line(st), flush=True)
        return self.follow(args.workdir, st) if args.wait else 0

    def cmd_status(self, args: argparse.Namespace) -> int:
        st = _call(args.workdir, self.status_op)
        print(json.dumps(st, indent=1) if args.json else self.line(st))
        return 0

    def cmd_stop(self, args: argparse.Namespace) -> int:
        st = _call(args.workdir, self.stop_op, timeout_s=180.0)
        print(self.line(st) + (f"; 'transfertwin cps {self.noun} resume' continues it"
                               if st["state"] == "stopped" else ""))  # fmt: skip
        return 0

    def add(self, sub: argparse._SubParsersAction, status_help: str) -> None:
        """Add the `resume`, `status` and `stop` subcommands."""
        p = sub.add_parser("resume", help=f"resume the last {self.noun}")
        p.add_argument("--workdir", required=True)
        p.add_argument("--wait", action="store_true", help="follow the progress until it ends")
        p.set_defaults(func=self.cmd_resume)
        p = sub.add_parser("status", help=status_help)
        p.add_argument("--workdir", required=True)
        p.add_argument("--json", action="store_true", help="the status as one JSON document")
        p.set_defaults(func=self.cmd_status)
        p = sub.add_parser("stop", help=f"stop the {self.noun} after the experiments in flight")
        p.add_argument("--workdir", required=True)
        p.set_defaults(func=self.cmd_stop)


#: The study's `resume`, `status` and `stop` (a study stopped, or failed on a passing
#: fault, resumes with an empty plan).
STUDY = Steering("study", ("StartStudy", "", ""), "StudyStatus", "StopStudy",
                 lambda st: status_line(st), lambda wd, st: _follow(wd, st))  # fmt: skip


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
    STUDY.add(ssub, "state, progress, rate, ETA and store of the study")
