"""`transfertwin cps campaign start|status|stop|resume`: calibration campaigns the floor's
Experiment Manager runs on the floor's physical units (docs/architecture.md, "Calibration
campaigns").

Exit codes: 0 done (``start --wait``: the campaign finished), 2 bad input or a refusal by
the Experiment Manager (one line on stderr), 3 the campaign failed (``--wait``), 130
interrupted while following (the campaign goes on in the Experiment Manager).
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

from transfertwin._errors import InputError
from transfertwin.cli._cps_study import Steering, _call

__all__ = ["register"]

#: Exit code of `start --wait` when the campaign failed.
EXIT_FAILED = 3

#: Request keys a flag of `start` sets (flag dest → JSON key).
_FLAGS = {"objects": "objects", "experiments": "experiments", "runs": "runs",
          "validation_runs": "validation_runs", "theta_step": "theta_step", "seed": "seed",
          "workers": "workers", "tune_trials": "tune_trials", "design": "design",
          "object_prior": "object_prior", "min_face_rows": "min_face_rows",
          "sampling": "sampling"}  # fmt: skip


def _delta(ci) -> str:
    """The paired bootstrap interval of after − before and what it decides: calibration
    helped or hurt only when the interval excludes 0 (a handful of held-out rows seldom
    decides anything)."""
    if not ci:
        return ""
    low, high = float(ci[0]), float(ci[1])
    verdict = "better" if low > 0 else "worse" if high < 0 else "undecided"
    return f" (after − before [{low:+.3f}, {high:+.3f}]: {verdict})"


def status_line(st: dict) -> str:
    """One line: campaign, state, stage, E^P and floor time, and the result once done."""
    if not st.get("campaign"):
        return f"campaign: {st['state']}"
    line = (f"campaign {st['campaign']}: {st['state']}"
            + (f", {st['stage']} {st.get('done', 0)}/{st.get('total', 0)}"
               if st.get("stage") and st["state"] in ("running", "stopping") else "")
            + f"; {st.get('plant_experiments', 0)} E^P on the floor's units, "
              f"{st.get('floor_s', 0):.0f} s of floor time; folder {st.get('folder')}")  # fmt: skip
    s = st.get("summary")
    if s:
        held = f" {s['held_out']}" if s.get("held_out") is not None else ""
        line += (f"; F0.5 on{held} held-out E^P {s['f05_before']:.3f} before, "
                 f"{s['f05_after']:.3f} after calibration{_delta(s.get('f05_delta_ci'))}; "
                 f"best/worst states that differ from the plant "
                 f"{s['significant_best']}/{s['significant_worst']}")  # fmt: skip
    return line + (f"; error: {st['error']}" if st.get("error") else "")


def _follow(workdir: str, first: dict) -> int:
    """Show the campaign's progress, a bar per stage, until it ends; its exit code."""
    from rich.console import Console

    from transfertwin.cli._progress import progress_bar

    console = Console(stderr=True)
    st = first
    try:
        while st["state"] in ("starting", "running", "stopping"):
            stage = st.get("stage") or "starting"
            with progress_bar(f"{stage[:48]}", console) as on_progress:
                while st["state"] in ("starting", "running", "stopping") and \
                        (st.get("stage") or "starting") == stage:  # fmt: skip
                    on_progress(int(st.get("done") or 0), int(st.get("total") or 0))
                    time.sleep(0.5)
                    st = _call(workdir, "CampaignStatus")
    except KeyboardInterrupt:
        print("not following any more; the campaign goes on ('transfertwin cps campaign "
              "stop' stops it)", file=sys.stderr)  # fmt: skip
        return 130
    print(status_line(st))
    return EXIT_FAILED if st["state"] == "failed" else 0


def _request(args: argparse.Namespace) -> str:
    """The JSON request: the file's (``--request``), flags over it."""
    doc: dict = {}
    if args.request:
        try:
            doc = json.loads(Path(args.request).read_text())
        except OSError as exc:
            raise InputError(f"--request {args.request}: cannot read "
                             f"({exc.strerror or exc})") from None  # fmt: skip
        except json.JSONDecodeError as exc:
            raise InputError(f"--request {args.request}: not JSON ({exc})") from None
        if not isinstance(doc, dict):
            raise InputError(f"--request {args.request}: a JSON object is expected")
    for dest, key in _FLAGS.items():
        value = getattr(args, dest)
        if value is not None:
            doc[key] = value
    return json.dumps(doc)


def cmd_start(args: argparse.Namespace) -> int:
    """Start (or resume: the same request) a campaign."""
    st = _call(args.workdir, "StartCampaign", _request(args), timeout_s=120.0)
    print(status_line(st), flush=True)
    return _follow(args.workdir, st) if args.wait else 0


#: The campaign's `resume` (an empty request: the last campaign), `status` and `stop`.
CAMPAIGN = Steering("campaign", ("StartCampaign", ""), "CampaignStatus", "StopCampaign",
                    lambda st: status_line(st), lambda wd, st: _follow(wd, st))  # fmt: skip


def register(csub: argparse._SubParsersAction) -> None:
    """Add `cps campaign start|status|stop|resume`."""
    camp = csub.add_parser("campaign", help="calibrate the twin on the floor's physical units "
                                            "(the Experiment Manager's campaigns)")  # fmt: skip
    sub = camp.add_subparsers(dest="campaign_command", required=True, parser_class=type(camp))
    p = sub.add_parser("start", help="start a campaign (the same request resumes it)")
    p.add_argument("--workdir", required=True, help="the floor's work folder (cps up --floor)")
    p.add_argument("--request", help="request.json (keys as the flags' names with '_'); "
                                     "flags given override it")  # fmt: skip
    p.add_argument("--objects", help="the floor's objects to calibrate and predict, e.g. "
                                     "o1,o3 (default: all)")  # fmt: skip
    p.add_argument("--experiments", type=int, help="K physical calibration experiments (E^P) "
                   "on the floor's physical units (default 40)")  # fmt: skip
    p.add_argument("--runs", type=int, help="runs per state and per replayed row (default 4)")
    p.add_argument("--validation-runs", type=int,
                   help="physical and virtual experiments (E^P, E^V) per object's best "
                   "and worst state (default 4)")  # fmt: skip
    p.add_argument("--theta-step", type=int, help="θ grid of the prediction (default 30)")
    p.add_argument("--seed", type=int, help="the twin's seed (default 0)")
    p.add_argument("--workers", type=int, help="worker processes of the virtual "
                                               "experiments (default 2, at least 2)")
    p.add_argument("--tune-trials", type=int, help="TPE trials over mu and the gap "
                                                   "(default 0: objects only)")
    p.add_argument("--design", choices=("space-filling", "random"),
                   help="the calibration states: space-filling (default; a Latin hypercube "
                        "over face and θ per object) or random (the study's)")  # fmt: skip
    p.add_argument("--object-prior", choices=("plain", "shipped"),
                   help="what object calibration moves from: each face's shipped feature "
                        "(default) or the plain body (the study's)")  # fmt: skip
    p.add_argument("--min-face-rows", type=int, help="training rows a face needs before its "
                                                     "depth is searched (default 1)")
    p.add_argument("--sampling", choices=("adaptive", "exhaustive"),
                   help="how the prediction spends its runs: adaptive (default, as the "
                        "on-the-fly predictions) or exhaustive (every state alike)")  # fmt: skip
    p.add_argument("--wait", action="store_true", help="follow the progress until it ends")
    p.set_defaults(func=cmd_start)
    CAMPAIGN.add(sub, "state, progress, floor time and result of the campaign")
