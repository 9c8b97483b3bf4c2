"""`transfertwin study run|status|export` and `analyze`: full-state studies (Sec. 6.6)."""

from __future__ import annotations

import argparse
import sys
from contextlib import ExitStack
from pathlib import Path

from rich.console import Console
from rich.table import Table

from transfertwin._errors import InputError
from transfertwin.cli._common import (
    add_executor_args,
    executor_from_args,
    positive_int,
    worker_count,
)
from transfertwin.cli._paths import out_dir, out_file
from transfertwin.cli._progress import progress_bar

__all__ = ["register"]


def _plan_from_args(args: argparse.Namespace):  # -> StudyPlan
    from transfertwin.sim import DockingError
    from transfertwin.study.docking import FixedDockingError, docking_model
    from transfertwin.study.experiment import PRESETS, StudyPlan, load_profile, parse_objects

    preset = PRESETS[args.preset]
    objects = parse_objects(args.objects) if args.objects else preset.objects
    profile_name, scene = ("default", None)
    if args.profile:
        profile_name, scene = load_profile(args.profile)
    kwargs = {"scene": scene} if scene is not None else {}
    if args.dock_error:
        docking = FixedDockingError(DockingError.from_text(args.dock_error))
    else:
        docking = docking_model(args.docking, args.docking_csv)
    return StudyPlan(
        **_sampling_from_args(args),
        objects=objects,
        theta_step=args.theta_step if args.theta_step is not None else preset.theta_step,
        runs=args.runs if args.runs is not None else preset.runs,
        seed=args.seed,
        docking=docking,
        profile_name=profile_name,
        units=args.units,
        leg=args.leg,
        **kwargs,
    )


_ADAPTIVE_OPTIONS = {  # CLI option → AdaptivePolicy field
    "adaptive_first_runs": "first_runs",
    "adaptive_batch": "batch_runs",
    "adaptive_interval": "interval",
    "adaptive_confidence": "confidence",
    "adaptive_epsilon": "epsilon",
}


def _sampling_from_args(args: argparse.Namespace) -> dict[str, object]:
    """``sampling`` and ``sampling_options`` of the plan; adaptive settings are checked."""
    given = {
        f: getattr(args, o) for o, f in _ADAPTIVE_OPTIONS.items() if getattr(args, o) is not None
    }
    if args.sampling != "adaptive":
        if given:
            opts = ", ".join(f"--{o.replace('_', '-')}" for o in _ADAPTIVE_OPTIONS)
            raise InputError(f"{opts} need --sampling adaptive")
        return {}
    from transfertwin.study.adaptive import AdaptivePolicy

    policy = AdaptivePolicy(**given)  # validates
    return {"sampling": "adaptive", "sampling_options": tuple(policy.describe().items())}


def run_summary_line(ran: int, seconds: float, done: int, planned: int) -> str:
    """The line after a study run. Its rate is wall-clock over the whole command, start-up
    of the workers included, so it is lower than the progress bar's recent rate."""
    rate = ran / seconds if seconds > 0 else 0.0
    return (
        f"{ran} new results in {seconds:.1f} s ({rate:.2f} exp/s wall-clock, including "
        f"start-up; the bar shows the recent rate); {done}/{planned} done"
    )


def cmd_study_run(args: argparse.Namespace) -> int:
    """Run (or resume) a full-state study into a SQLite db, on local workers or Ray."""
    from transfertwin.store import SQLiteResultStore
    from transfertwin.study.experiment import check_plan, run_study, summarize

    db = out_file(args.db, (".sqlite", ".sqlite3", ".db"))
    workers = worker_count(args.workers)
    if args.max_experiments is not None:
        positive_int("--max-experiments", args.max_experiments)
    executor = executor_from_args(args, workers)
    plan = _plan_from_args(args)
    check_plan(plan)  # every mesh loads before the db is created
    console = Console(stderr=True)
    with ExitStack() as stack:
        if executor is not None:
            stack.enter_context(executor)  # Ray or a GPU reachable before the db is created
            if args.executor == "warp":
                runner = f"MuJoCo Warp ({executor.device}, {executor.worlds} worlds per batch)"
            else:
                where = args.address or "local Ray"
                runner = f"Ray ({where}, {executor.cpus} CPUs, {executor.chunk_size} per task)"
        else:
            runner = f"{workers} workers"
        store = stack.enter_context(SQLiteResultStore(db))
        store.init_plan(plan.plan_hash, plan.to_json())  # refuses another plan up front
        adaptive = plan.sampling == "adaptive"
        console.print(
            f"plan {plan.plan_hash[:12]}: {len(plan.objects)} objects x "
            f"{len(plan.states())} states x {'at most ' if adaptive else ''}{plan.runs} runs = "
            f"{plan.n_experiments} experiments, {plan.sampling} sampling, "
            f"profile {plan.profile_name}, {runner}"
        )
        with progress_bar("study", console) as on_progress:
            if adaptive:
                from transfertwin.study.adaptive import run_adaptive

                outcome = run_adaptive(plan, store, workers=workers, on_progress=on_progress,
                                       max_experiments=args.max_experiments,
                                       executor=executor)  # fmt: skip
            else:
                outcome = run_study(plan, store, workers=workers, on_progress=on_progress,
                                    max_experiments=args.max_experiments,
                                    executor=executor)  # fmt: skip
        _print_summary(summarize(store.rows()), console)
        console.print(run_summary_line(outcome.ran, outcome.seconds, store.count(),
                                       plan.n_experiments))  # fmt: skip
        if adaptive:
            state = "finished" if outcome.finished else "not finished: rerun to continue"
            console.print(
                f"adaptive: {outcome.runs} runs = {outcome.fraction:.1%} of the exhaustive "
                f"{plan.n_experiments}; {state}"
            )
    if outcome.interrupted:
        console.print("interrupted: results so far are stored; rerun the same command to resume")
        return 130
    return 0


def _print_summary(summaries, console: Console) -> None:
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
    from transfertwin.study.experiment import StudyPlan

    with SQLiteResultStore(args.db, create=False) as store:
        stored = store.plan()
        planned = StudyPlan.from_json(stored.plan_json).n_experiments if stored else 0
        print(f"db: {args.db}")
        print(f"plan: {stored.plan_hash[:12] if stored else '-'}")
        plan = StudyPlan.from_json(stored.plan_json) if stored else None
        print(f"sampling: {plan.sampling if plan else '-'}")
        print(
            f"done: {store.count()}/{planned}"
            + (" (at most)" if plan and plan.sampling == "adaptive" else "")
        )
        for status, n in sorted(store.count_by_status().items()):
            print(f"  {status}: {n}")
    return 0


def cmd_study_export(args: argparse.Namespace) -> int:
    """Write the result table of a study db as CSV or Parquet."""
    from transfertwin.store import SQLiteResultStore, export_results

    out = out_file(args.out, (".csv", ".parquet"))
    with SQLiteResultStore(args.db, create=False) as store:
        path = export_results(store.rows(), out)
    print(path)
    return 0


def _progress(plan_json: str, rows: list[dict[str, object]]):  # -> StudyProgress
    """Done/planned of a study db's rows against its stored plan."""
    from transfertwin.report import StudyProgress
    from transfertwin.study.experiment import StudyPlan

    plan = StudyPlan.from_json(plan_json)
    keys = {(r["object_id"], r["face"], r["conveyor"], r["theta_deg"]) for r in rows}
    return StudyProgress(
        done=len(rows), planned=plan.n_experiments, states_done=len(keys),
        states_planned=len(plan.objects) * len(plan.states()),
        adaptive=plan.sampling == "adaptive",
    )  # fmt: skip


def cmd_analyze(args: argparse.Namespace) -> int:
    """Per-state statistics, best/worst states, plots and report of a result table.

    A study db whose plan is not finished is analysed as it stands; the report opens with
    a banner and stderr gets one line saying done/planned."""
    from transfertwin.report import analyze_and_report, partial_line
    from transfertwin.store import SQLITE_SUFFIXES, SQLiteResultStore, read_results
    from transfertwin.study.experiment import plan_parameters

    out = out_dir(args.out)
    rows = read_results(args.results)
    params: dict[str, object] = {"results": str(args.results), "rows": len(rows)}
    progress = None
    if Path(args.results).suffix.lower() in SQLITE_SUFFIXES:
        with SQLiteResultStore(args.results, create=False) as store:
            stored = store.plan()
        if stored is not None:
            params.update(plan_parameters(stored.plan_json))
            progress = _progress(stored.plan_json, rows)
    _, report = analyze_and_report(rows, out, params, progress=progress)
    if progress is not None and progress.partial:
        print(f"transfertwin: {partial_line(progress)}", file=sys.stderr)
    print(report)
    return 0


def register(sub: argparse._SubParsersAction) -> None:
    """Add `study run|status|export` and `analyze`."""
    study = sub.add_parser("study", help="full-state digital-twin study (Sec. 6.6)")
    ssub = study.add_subparsers(dest="study_command", required=True, parser_class=type(study))
    p = ssub.add_parser("run", help="run or resume a study into a SQLite db")
    p.add_argument("--db", required=True, help="SQLite result store (created if missing)")
    p.add_argument("--objects", help="o1,o18,... | all | mesh paths (default: preset)")
    p.add_argument("--runs", type=int, help="repetitions per state (default: preset)")
    p.add_argument("--theta-step", type=int, help="keep θ multiples of this; it must divide 360 "
                   "(default: preset)")  # fmt: skip
    p.add_argument("--preset", choices=("quick", "full"), default="quick")
    p.add_argument("--workers", type=int, help="worker processes (default: all cores)")
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--profile", help="physics profile TOML (default: built-in defaults)")
    p.add_argument("--units", default="m", help="length unit of mesh files (default m)")
    p.add_argument("--docking", default="copula", help="docking-error model: "
                   "copula, copula-per-station, resample or MODEL.json from 'docking fit' "
                   "(default: copula fitted to the measured errors)")  # fmt: skip
    p.add_argument("--docking-csv", help="measured docking errors to fit or resample "
                   "(default: the shipped calibration experiments)")  # fmt: skip
    p.add_argument("--dock-error", help="X_MM,Y_MM,THETA_DEG: one fixed docking error for all "
                   "experiments instead of resampled measurements")  # fmt: skip
    p.add_argument("--leg", choices=("round-trip", "pick-up", "operation"),
                   default="round-trip", help="what each experiment runs: the object there "
                   "and back from the module (round-trip, the study's virtual experiment "
                   "E^V), a floor's pick-up from a unit onto the module (pick-up), or the "
                   "pick-up and then the "
                   "delivery at another unit (operation)")  # fmt: skip
    p.add_argument("--max-experiments", type=int, help="stop after this many new results")
    p.add_argument("--sampling", choices=("exhaustive", "adaptive"), default="exhaustive",
                   help="exhaustive: --runs runs per state; adaptive: rounds of runs where "
                   "they can change the best/worst state, at most --runs per state")  # fmt: skip
    p.add_argument("--adaptive-first-runs", type=int, help="runs per state in the first "
                   "round (default 5)")  # fmt: skip
    p.add_argument("--adaptive-batch", type=int, help="runs added per chosen state and "
                   "round (default 5)")  # fmt: skip
    p.add_argument("--adaptive-interval", help="beta (Jeffreys posterior, default) or "
                   "clopper-pearson (exact, Bonferroni over looks)")  # fmt: skip
    p.add_argument("--adaptive-confidence", type=float, help="level of the per-state "
                   "intervals (default 0.9)")  # fmt: skip
    p.add_argument("--adaptive-epsilon", type=float, help="indifference zone in success "
                   "share (default 0.1)")  # fmt: skip
    add_executor_args(p, warp=True)
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
