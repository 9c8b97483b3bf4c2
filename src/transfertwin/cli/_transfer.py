"""`transfertwin transfer|states|objects|demo`: single experiments, the state set, the cores."""

from __future__ import annotations

import argparse
import json
import math
import sys
from pathlib import Path
from typing import TYPE_CHECKING

from rich.console import Console
from rich.table import Table

from transfertwin._errors import InputError
from transfertwin.cli._common import add_state_args
from transfertwin.cli._paths import out_dir, out_file
from transfertwin.cli._progress import progress_bar

if TYPE_CHECKING:
    from transfertwin.study.experiment import ExperimentResult

__all__ = ["register"]


def hull_notice(ref: str, units: str = "m") -> str:
    """The line to print before a mesh's first CoACD decomposition (seconds to minutes),
    or '' when its hulls are shipped or cached (or the reference is unusable: the
    experiment then reports that itself)."""
    from transfertwin.objects import MeshError, hull_cache_path

    try:
        path = hull_cache_path(ref, units=units)
    except (InputError, MeshError, OSError, ValueError):
        return ""
    if path is None or path.is_file():
        return ""
    return (
        f"computing convex hulls (CoACD) for {Path(ref).name}, once; cached by content hash "
        f"in {path.parent}"
    )


def cmd_transfer(args: argparse.Namespace) -> int:
    """One virtual experiment E^V: there and, if that worked, back."""
    from transfertwin.sim import DockingError, SceneConfig, render_strip
    from transfertwin.study.experiment import (
        ExperimentSpec,
        load_profile,
        run_experiment,
        system_for,
    )

    image = out_file(args.image, (".png",)) if args.image else None
    scene = load_profile(args.profile)[1] if args.profile else SceneConfig()
    if args.mu is not None:
        scene = scene.with_overrides(mu=args.mu)
    if args.gap_mm is not None:
        scene = scene.with_overrides(gap_m=args.gap_mm / 1000.0)
    spec = ExperimentSpec(
        object_ref=args.object,
        face=args.face,
        conveyor=args.conveyor,
        theta_deg=args.theta,
        docking_error=DockingError.from_text(args.dock_error),
        scene=scene,
        seed=args.seed,
        units=args.units,
        record=image is not None,
    )
    notice = hull_notice(args.object, args.units)
    if notice:
        print(notice, file=sys.stderr, flush=True)
    result = run_experiment(spec, sensor=args.sensor)
    if image is not None:
        system = system_for(spec.object_ref, spec.units, spec.scene)
        poses = [(f.phase, f.t_s, f.qpos) for f in result.frames]
        render_strip(system, poses, image, title=strip_title(result), travel=TRAVEL)
    row = result.row()
    if args.json:
        clean = {k: (None if isinstance(v, float) and math.isnan(v) else v) for k, v in row.items()}
        for key in ("state_pre", "state_end_1", "state_end_2"):
            clean[key] = json.loads(clean[key]) if clean[key] else None
        print(json.dumps(clean))
    else:
        _print_result(row)
    return 0


#: Direction the belts run in each recorded phase of E^V (+1: TM → TU).
TRAVEL = {"there": 1, "back": -1}


def _leg(y: int | None, t_end_s: float) -> str:
    """One transfer's outcome in words: 'delivered in 3.58 s', 'failed after 2.00 s'."""
    if y is None:
        return "not determined"
    when = "" if math.isnan(t_end_s) else (f" in {t_end_s:.2f} s" if y == 1 else
                                           f" after {t_end_s:.2f} s")  # fmt: skip
    return ("delivered" if y == 1 else "failed") + when


def strip_title(result: ExperimentResult) -> list[str]:
    """Header lines of a strip image: the state, the docking error, and each transfer's
    outcome in words (a transfer that was not attempted says so; never 'None')."""
    from transfertwin.replay import outcome_text, status_text

    x, y, t = result.dock_err_x_mm, result.dock_err_y_mm, result.dock_err_theta_deg
    lines = [
        f"{result.object_id}: face {result.face}, conveyor {result.conveyor}, "
        f"θ = {result.theta_deg}°, seed {result.seed}; docking error x = {x:.2f} mm, "
        f"y = {y:.2f} mm, θ = {t:.2f}°"
    ]
    if result.status != "ok":
        lines.append(status_text(result.status, result.message))
        return lines
    there = "TM → TU: " + _leg(result.y1, result.t_end_1_s)
    if result.y2 is None:
        back = "TU → TM: not attempted (the transfer there failed)"
    else:
        back = "TU → TM: " + _leg(result.y2, result.t_end_2_s)
    lines.append(f"{there};  {back};  {outcome_text(result.row())}")
    return lines


def result_lines(row: dict[str, object]) -> list[str]:
    """What `transfer` prints: the experiment, then its outcome in words (the machine form,
    status, y1, y2 and success, is `--json`'s)."""
    from transfertwin.replay import outcome_text, state_text

    x, y, t = (float(row[k]) for k in ("dock_err_x_mm", "dock_err_y_mm", "dock_err_theta_deg"))
    return [
        f"{state_text(row)}, seed {row['seed']}; docking error x {x:.2f} mm, y {y:.2f} mm, "
        f"θ {t:.2f}°",
        outcome_text(row),
    ]


def _print_result(row: dict[str, object]) -> None:
    for line in result_lines(row):
        print(line)


def cmd_states(args: argparse.Namespace) -> int:
    """Print the experiment state set (Eq. 6.7–6.10) as CSV."""
    from transfertwin.ots import experiment_states, filter_theta_step, states_csv
    from transfertwin.study.experiment import check_theta_step

    states = experiment_states()
    if args.theta_step:
        check_theta_step(args.theta_step)
        states = filter_theta_step(states, args.theta_step)
    sys.stdout.write(states_csv(states))
    return 0


def cmd_objects_list(args: argparse.Namespace) -> int:
    """List the built-in cores."""
    from transfertwin.objects import builtin_ids, core_spec, load_object

    table = Table(title="built-in starter-motor cores")
    for col in ("id", "length mm", "mass kg", "hulls", "wear"):
        table.add_column(col)
    for i, oid in enumerate(builtin_ids(), start=1):
        obj = load_object(oid)
        spec = core_spec(i)
        ext = obj.mesh.extents * 1000
        table.add_row(
            oid, f"{ext[0]:.0f}", f"{obj.mass.mass_kg:.2f}", str(len(obj.hulls)),
            ", ".join(getattr(spec, "wear", ()) or ()) or "-",
        )  # fmt: skip
    Console().print(table)
    return 0


def cmd_objects_export(args: argparse.Namespace) -> int:
    """Write an object's mesh as STL."""
    from transfertwin.objects import export_object

    out = out_file(args.out, (".stl",))
    export_object(args.id, out)
    print(out)
    return 0


def demo_row(r: ExperimentResult) -> list[str]:
    """A demo table row: the state and the outcome in words (`outcome_text`: never a code
    or 'None')."""
    from transfertwin.replay import outcome_text

    return [r.face, r.conveyor, str(r.theta_deg), outcome_text(r.row())]


def cmd_demo(args: argparse.Namespace) -> int:
    """A short demo of single transfers with a real docking error."""
    from transfertwin.study.experiment import check_theta_step, run_demo

    check_theta_step(args.theta_step)
    out = out_dir(args.out)
    console = Console()
    with progress_bar(f"E^V {args.object}", console) as on_progress:
        results, path = run_demo(
            out, object_ref=args.object, step_deg=args.theta_step, on_progress=on_progress
        )
    table = Table(title=f"{args.object}: E^V with the docking error of real experiment 0")
    for col in ("face", "conveyor", "θ (°)", "outcome"):
        table.add_column(col)
    for r in results:
        table.add_row(*demo_row(r))
    console.print(table)
    ok = [r for r in results if r.status == "ok"]
    share = sum(r.success for r in ok) / len(ok) if ok else float("nan")
    console.print(f"success share over {len(ok)} valid states: {share:.2f}")
    console.print(f"results: {path}")
    return 0


def register(sub: argparse._SubParsersAction) -> None:
    """Add `transfer`, `states`, `objects list|export` and `demo`."""
    p = sub.add_parser("transfer", help="run one virtual transfer experiment (E^V)")
    add_state_args(p)
    p.add_argument("--profile", help="physics profile TOML or built-in name (default: defaults)")
    p.add_argument("--mu", type=float, help="dynamic friction (default: the profile's, 0.489)")
    p.add_argument("--gap-mm", type=float, help="nominal gap (default: the profile's, 11.88)")
    p.add_argument("--seed", type=int, default=0)
    p.add_argument(
        "--sensor", choices=("truth", "perception"), default="truth",
        help="object state from the simulator (truth) or the TM's depth camera "
        "(perception: scan, follow, one detected frame per sample; slower)",
    )  # fmt: skip
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.add_argument("--image", help="write a strip of frames from t0 to t_end to this PNG")
    p.set_defaults(func=cmd_transfer)
    p = sub.add_parser("states", help="print the 924 pre-transfer states as CSV")
    p.add_argument("--theta-step", type=int, default=0,
                   help="keep θ multiples of this; it must divide 360 "
                   "(default: every state)")  # fmt: skip
    p.set_defaults(func=cmd_states)
    objects = sub.add_parser("objects", help="built-in cores")
    osub = objects.add_subparsers(dest="objects_command", required=True, parser_class=type(objects))
    osub.add_parser("list", help="list built-in cores").set_defaults(func=cmd_objects_list)
    p = osub.add_parser("export", help="write a core's mesh as STL")
    p.add_argument("id")
    p.add_argument("--out", required=True)
    p.set_defaults(func=cmd_objects_export)
    p = sub.add_parser("demo", help="a short demo of single transfers")
    p.add_argument("--out", default="out/demo", help="output directory")
    p.add_argument("--object", default="o1",
                   help="built-in core id (o1..o37) or a mesh path (default o1)")  # fmt: skip
    p.add_argument("--theta-step", type=int, default=45,
                   help="θ every this many degrees; it must divide 360 (default 45)")  # fmt: skip
    p.set_defaults(func=cmd_demo)
