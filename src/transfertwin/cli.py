"""Command line interface: `transfertwin` / `python -m transfertwin`.

Thin: one function per subcommand that calls the public API. Logging is configured here
only. Exit codes: 0 success, 2 bad input (one line on stderr, no partial output files),
1 internal error.
"""

from __future__ import annotations

import argparse
import json
import logging
import math
import sys
from collections.abc import Sequence
from pathlib import Path

from transfertwin._errors import InputError

__all__ = ["main"]

log = logging.getLogger("transfertwin")


class _Parser(argparse.ArgumentParser):
    """argparse with one-line errors and exit code 2."""

    def error(self, message: str) -> None:  # type: ignore[override]
        raise InputError(message)


def _parse_dock_error(text: str):  # -> DockingError
    from transfertwin.sim import DockingError

    parts = text.split(",")
    try:
        values = [float(p) for p in parts]
    except ValueError:
        values = []
    if len(values) != 3:
        raise InputError(f"--dock-error expects X_MM,Y_MM,THETA_DEG, got {text!r}")
    return DockingError.from_mm_deg(*values)


def _scene(args: argparse.Namespace):  # -> SceneConfig
    from transfertwin.sim import SceneConfig

    return SceneConfig(mu=args.mu, gap_m=args.gap_mm / 1000.0)


def _check_out_path(path: str, suffixes: tuple[str, ...]) -> Path:
    out = Path(path)
    if out.suffix.lower() not in suffixes:
        raise InputError(f"{path}: expected a file ending in {' or '.join(suffixes)}")
    if out.parent and not out.parent.exists():
        raise InputError(f"{path}: directory {out.parent} does not exist")
    return out


def cmd_transfer(args: argparse.Namespace) -> int:
    """One virtual experiment E^V: there and, if that worked, back."""
    from transfertwin.study import ExperimentSpec, run_experiment, system_for

    image = _check_out_path(args.image, (".png",)) if args.image else None
    spec = ExperimentSpec(
        object_ref=args.object,
        face=args.face,
        conveyor=args.conveyor,
        theta_deg=args.theta,
        docking_error=_parse_dock_error(args.dock_error),
        scene=_scene(args),
        seed=args.seed,
        units=args.units,
        record=image is not None,
    )
    result = run_experiment(spec)
    if image is not None:
        from transfertwin.sim._render import render_strip

        system = system_for(spec.object_ref, spec.units, spec.scene)
        poses = [(f.phase, f.t_s, f.qpos) for f in result.frames]
        title = (
            f"{result.object_id} {spec.face} {spec.conveyor} theta={spec.theta_deg} "
            f"y1={result.y1} y2={result.y2} success={result.success} ({result.status})"
        )
        render_strip(system, poses, image, title=title)
    row = result.row()
    if args.json:
        clean = {k: (None if isinstance(v, float) and math.isnan(v) else v) for k, v in row.items()}
        for key in ("state_pre", "state_end_1", "state_end_2"):
            clean[key] = json.loads(clean[key]) if clean[key] else None
        print(json.dumps(clean))
    else:
        _print_result(row)
    return 0


def _print_result(row: dict[str, object]) -> None:
    from rich.console import Console
    from rich.table import Table

    table = Table(title="virtual transfer experiment E^V", show_header=False)
    for key in (
        "object_id", "face", "conveyor", "theta_deg", "seed", "dock_err_x_mm", "dock_err_y_mm",
        "dock_err_theta_deg", "status", "y1", "y2", "success", "t_end_1_s", "t_end_2_s",
        "t_end_s", "message",
    ):  # fmt: skip
        value = row[key]
        text = f"{value:.3f}" if isinstance(value, float) else str(value)
        table.add_row(key, "-" if value is None or text == "nan" else text)
    Console().print(table)


def cmd_states(args: argparse.Namespace) -> int:
    """Print the experiment state set (Eq. 6.7–6.10) as CSV."""
    from transfertwin.ots import experiment_states, filter_theta_step, states_csv

    states = experiment_states()
    if args.theta_step:
        states = filter_theta_step(states, args.theta_step)
    sys.stdout.write(states_csv(states))
    return 0


def cmd_objects_list(args: argparse.Namespace) -> int:
    """List the built-in cores."""
    from rich.console import Console
    from rich.table import Table

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

    out = _check_out_path(args.out, (".stl",))
    export_object(args.id, out)
    print(out)
    return 0


def cmd_demo(args: argparse.Namespace) -> int:
    """The main job on built-in defaults (for now: a short demo of single transfers)."""
    from transfertwin.study._demo import run_demo

    run_demo(Path(args.out), object_ref=args.object, step_deg=args.theta_step)
    return 0


def _plan_from_args(args: argparse.Namespace):  # -> StudyPlan
    from transfertwin.study import PRESETS, StudyPlan, parse_objects
    from transfertwin.study._profile import load_profile

    preset = PRESETS[args.preset]
    objects = parse_objects(args.objects) if args.objects else preset.objects
    profile_name, scene = ("default", None)
    if args.profile:
        profile_name, scene = load_profile(args.profile)
    kwargs = {"scene": scene} if scene is not None else {}
    return StudyPlan(
        objects=objects,
        theta_step=args.theta_step if args.theta_step is not None else preset.theta_step,
        runs=args.runs if args.runs is not None else preset.runs,
        seed=args.seed,
        docking=_docking_model(args),
        profile_name=profile_name,
        units=args.units,
        **kwargs,
    )


def _docking_model(args: argparse.Namespace):  # -> DockingErrorModel
    """The study's docking-error model from --dock-error / --docking / --docking-csv."""
    from transfertwin.study import (
        FixedDockingError,
        GaussianCopula,
        PerStationCopula,
        ResampledDockingErrors,
        docking_model_from_dict,
        measured_docking_errors,
    )

    if args.dock_error:
        return FixedDockingError(_parse_dock_error(args.dock_error))
    kind = args.docking
    if kind == "resample":
        return ResampledDockingErrors.from_csv(args.docking_csv)
    if kind == "copula":
        return GaussianCopula.fit(measured_docking_errors(args.docking_csv))
    if kind == "copula-per-station":
        from transfertwin.cli_docking import read_errors

        errors, units = read_errors(args.docking_csv, need_units=True)
        return PerStationCopula.fit(errors, units)
    path = Path(kind)
    if path.suffix.lower() != ".json" or not path.is_file():
        raise InputError(f"--docking {kind!r}: expected copula, copula-per-station, resample "
                         "or a model JSON written by 'transfertwin docking fit'")  # fmt: skip
    try:
        desc = json.loads(path.read_text())
    except (OSError, ValueError) as exc:
        raise InputError(f"{kind}: cannot read docking model: {exc}") from None
    return docking_model_from_dict(desc)


def cmd_study_run(args: argparse.Namespace) -> int:
    """Run (or resume) a full-state study into a SQLite store."""
    import os

    from rich.console import Console

    from transfertwin.store import SQLiteResultStore
    from transfertwin.study import run_study, summarize

    plan = _plan_from_args(args)
    workers = args.workers or (os.cpu_count() or 1)
    db = Path(args.db)
    if not db.parent.exists():
        raise InputError(f"{args.db}: directory {db.parent} does not exist")
    console = Console(stderr=True)
    with SQLiteResultStore(db) as store:
        store.init_plan(plan.plan_hash, plan.to_json())  # refuses another plan up front
        console.print(
            f"plan {plan.plan_hash[:12]}: {len(plan.objects)} objects x "
            f"{len(plan.states())} states x {plan.runs} runs = {plan.n_experiments} experiments, "
            f"profile {plan.profile_name}, {workers} workers"
        )
        outcome = run_study(plan, store, workers=workers, console=console,
                            max_experiments=args.max_experiments)  # fmt: skip
        _print_summary(summarize(store.rows()), console)
        console.print(
            f"{outcome.ran} new results in {outcome.seconds:.1f} s ({outcome.rate:.2f} exp/s); "
            f"{store.count()}/{plan.n_experiments} done"
        )
    if outcome.interrupted:
        console.print("interrupted: results so far are stored; rerun the same command to resume")
        return 130
    return 0


def _print_summary(summaries, console) -> None:
    from rich.table import Table

    table = Table(title="per-object summary")
    for col in ("object", "done", "ok", "invalid", "unstable", "error", "success share"):
        table.add_column(col)
    for s in summaries:
        table.add_row(
            s.object_id, str(s.done), str(s.ok), str(s.by_status.get("invalid", 0)),
            str(s.by_status.get("unstable", 0)), str(s.by_status.get("error", 0)),
            f"{s.success_share:.3f}",
        )  # fmt: skip
    console.print(table)


def cmd_study_status(args: argparse.Namespace) -> int:
    """Show done/planned and rows by status of a study db."""
    from transfertwin.store import SQLiteResultStore
    from transfertwin.study import StudyPlan

    with SQLiteResultStore(args.db, create=False) as store:
        stored = store.plan()
        planned = StudyPlan.from_json(stored.plan_json).n_experiments if stored else 0
        print(f"db: {args.db}")
        print(f"plan: {stored.plan_hash[:12] if stored else '-'}")
        print(f"done: {store.count()}/{planned}")
        for status, n in sorted(store.count_by_status().items()):
            print(f"  {status}: {n}")
    return 0


def cmd_study_export(args: argparse.Namespace) -> int:
    """Write the result table of a study db as CSV or Parquet."""
    from transfertwin.store import SQLiteResultStore, export_results

    out = _check_out_path(args.out, (".csv", ".parquet"))
    with SQLiteResultStore(args.db, create=False) as store:
        path = export_results(store.rows(), out)
    print(path)
    return 0


def cmd_analyze(args: argparse.Namespace) -> int:
    """Per-state statistics, best/worst states, plots and report of a result table."""
    from transfertwin.report import analyze_and_report
    from transfertwin.store import read_results

    rows = read_results(args.results)
    params: dict[str, object] = {"results": str(args.results), "rows": len(rows)}
    if Path(args.results).suffix.lower() in (".sqlite", ".sqlite3", ".db"):
        params.update(_study_params(args.results))
    _, report = analyze_and_report(rows, Path(args.out), params)
    print(report)
    return 0


def _study_params(db: str) -> dict[str, object]:
    """The stored plan of a study db, flattened for the report's parameter table."""
    import json

    from transfertwin.store import SQLiteResultStore

    with SQLiteResultStore(db, create=False) as store:
        stored = store.plan()
    if stored is None:
        return {}
    plan = json.loads(stored.plan_json)
    scene = plan.pop("scene", {})
    out = {f"plan.{k}": v for k, v in plan.items()}
    out.update({f"scene.{k}": v for k, v in scene.items() if not isinstance(v, dict)})
    for section in ("physics", "layout", "placement"):
        out.update({f"{section}.{k}": v for k, v in scene.get(section, {}).items()})
    return out


def _add_study(sub: argparse._SubParsersAction) -> None:
    study = sub.add_parser("study", help="full-state digital-twin study (Sec. 6.6)")
    ssub = study.add_subparsers(dest="study_command", required=True, parser_class=_Parser)
    p = ssub.add_parser("run", help="run or resume a study into a SQLite db")
    p.add_argument("--db", required=True, help="SQLite result store (created if missing)")
    p.add_argument("--objects", help="o1,o18,... | all | mesh paths (default: preset)")
    p.add_argument("--runs", type=int, help="repetitions per state (default: preset)")
    p.add_argument("--theta-step", type=int, help="keep θ multiples of this (default: preset)")
    p.add_argument("--preset", choices=("quick", "full"), default="quick")
    p.add_argument("--workers", type=int, default=0, help="worker processes (default: cores)")
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--profile", help="physics profile TOML (default: built-in defaults)")
    p.add_argument("--units", default="m", help="length unit of mesh files")
    p.add_argument("--docking", default="copula", help="docking-error model: copula "
                   "(default, fitted to the measured errors), copula-per-station, resample, "
                   "or MODEL.json from 'docking fit'")  # fmt: skip
    p.add_argument("--docking-csv", help="measured docking errors to fit or resample "
                   "(default: the shipped calibration experiments)")  # fmt: skip
    p.add_argument("--dock-error", help="X_MM,Y_MM,THETA_DEG: one fixed docking error for all "
                   "experiments instead of resampled measurements")  # fmt: skip
    p.add_argument("--max-experiments", type=int, help="stop after this many new results")
    p.set_defaults(func=cmd_study_run)
    p = ssub.add_parser("status", help="done/planned and rows by status")
    p.add_argument("--db", required=True)
    p.set_defaults(func=cmd_study_status)
    p = ssub.add_parser("export", help="write the result table as CSV or Parquet")
    p.add_argument("--db", required=True)
    p.add_argument("--out", required=True, help="FILE.csv or FILE.parquet")
    p.set_defaults(func=cmd_study_export)
    p = sub.add_parser("analyze", help="statistics, best/worst states, plots, report")
    p.add_argument("results", help="result table: SQLite db, CSV or Parquet")
    p.add_argument("--out", required=True, help="output directory")
    p.set_defaults(func=cmd_analyze)


def _add_transfer(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("transfer", help="run one virtual transfer experiment (E^V)")
    p.add_argument("--object", required=True, help="built-in core id (o1..o37) or a mesh path")
    p.add_argument("--units", default="m", help="length unit of a mesh file: m, cm, mm, in")
    p.add_argument("--face", required=True, help="front or back")
    p.add_argument("--conveyor", required=True, help="left, right or both")
    p.add_argument("--theta", required=True, type=int, help="yaw in integer degrees, -179..180")
    p.add_argument("--dock-error", default="0,0,0", help="X_MM,Y_MM,THETA_DEG (default 0,0,0)")
    p.add_argument("--mu", type=float, default=0.489, help="dynamic friction (default 0.489)")
    p.add_argument("--gap-mm", type=float, default=11.88, help="nominal gap (default 11.88)")
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.add_argument("--image", help="write a strip of frames from t0 to t_end to this PNG")
    p.set_defaults(func=cmd_transfer)


def build_parser() -> argparse.ArgumentParser:
    """The argument parser of every subcommand."""
    parser = _Parser(prog="transfertwin", description=__doc__.splitlines()[0])
    parser.add_argument("-v", "--verbose", action="store_true", help="debug logging")
    sub = parser.add_subparsers(dest="command", required=True, parser_class=_Parser)
    _add_transfer(sub)
    _add_study(sub)
    from transfertwin import cli_calibrate, cli_cps, cli_docking, cli_validate

    cli_calibrate.register(sub)
    cli_cps.register(sub)
    cli_docking.register(sub)
    cli_validate.register(sub)
    p = sub.add_parser("states", help="print the 924 pre-transfer states as CSV")
    p.add_argument("--theta-step", type=int, default=0, help="keep θ multiples of this")
    p.set_defaults(func=cmd_states)
    objects = sub.add_parser("objects", help="built-in cores")
    osub = objects.add_subparsers(dest="objects_command", required=True, parser_class=_Parser)
    osub.add_parser("list", help="list built-in cores").set_defaults(func=cmd_objects_list)
    p = osub.add_parser("export", help="write a core's mesh as STL")
    p.add_argument("id")
    p.add_argument("--out", required=True)
    p.set_defaults(func=cmd_objects_export)
    p = sub.add_parser("demo", help="main job on built-in defaults: a short transfer demo")
    p.add_argument("--out", default="out/demo", help="output directory")
    p.add_argument("--object", default="o1")
    p.add_argument("--theta-step", type=int, default=45)
    p.set_defaults(func=cmd_demo)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point; returns the exit code."""
    try:
        args = build_parser().parse_args(argv)
        logging.basicConfig(
            level=logging.DEBUG if args.verbose else logging.WARNING,
            format="%(levelname)s %(name)s: %(message)s",
        )
        return int(args.func(args))
    except InputError as exc:
        print(f"transfertwin: error: {exc}", file=sys.stderr)
        return 2
    except BrokenPipeError:  # e.g. `transfertwin states | head`
        sys.stderr.close()
        return 0
    except KeyboardInterrupt:
        print("transfertwin: interrupted", file=sys.stderr)
        return 130
    except Exception as exc:
        log.debug("internal error", exc_info=True)
        print(f"transfertwin: internal error: {type(exc).__name__}: {exc}", file=sys.stderr)
        return 1
