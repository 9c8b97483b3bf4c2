"""`transfertwin replay`: re-simulate one experiment and watch it in 3-D, or export it."""

from __future__ import annotations

import argparse
import json
import sys
import webbrowser
from pathlib import Path

from transfertwin._errors import InputError
from transfertwin.cli._paths import out_file

__all__ = ["register"]

_TRANSFER_ONLY = ("seed", "dock_error", "profile", "mu", "gap_mm")
_STATE = ("object", "face", "conveyor", "theta")


_PLANT_ONLY = ("plant_seed", "plant_seed_file", "plant_kind")


def _plant_row(args: argparse.Namespace):  # -> PlantRow
    from transfertwin.replay import plant_row

    given = [
        f"--{k.replace('_', '-')}"
        for k in (*_TRANSFER_ONLY, *_STATE, "db", "calibration", "run")
        if getattr(args, k) is not None
    ]
    if given:
        raise InputError(f"{', '.join(given)}: a plant row's experiment comes from its table "
                         "and its plant (give --row, and the plant)")  # fmt: skip
    if args.row is None:
        raise InputError("--plant-rows needs --row (the row's index in the table)")
    return plant_row(
        args.plant_rows,
        args.row,
        plant_seed=args.plant_seed,
        plant_seed_file=args.plant_seed_file,
        plant_kind=args.plant_kind,
    )


def _spec(args: argparse.Namespace):  # -> (ExperimentSpec, StudyRow | CalibrationRow | None)
    from transfertwin.replay import calibration_spec, study_spec, transfer_spec

    plant_given = [f"--{k.replace('_', '-')}" for k in _PLANT_ONLY if getattr(args, k) is not None]
    if plant_given:
        raise InputError(f"{', '.join(plant_given)}: only with --plant-rows (a plant's table)")
    if args.calibration is not None:
        given = [f"--{k.replace('_', '-')}" for k in (*_TRANSFER_ONLY, *_STATE, "db")
                 if getattr(args, k) is not None]  # fmt: skip
        if given:
            raise InputError(f"{', '.join(given)}: a calibration row's experiment comes from "
                             "its folder (give --row and --run only)")  # fmt: skip
        if args.row is None:
            raise InputError("--calibration needs --row (the real row's index)")
        found = calibration_spec(args.calibration, args.row, args.run or 0)
        return found.spec, found
    if args.row is not None:
        raise InputError("--row needs --calibration (a 'calibrate run' folder)")
    missing = [f"--{k}" for k in _STATE if getattr(args, k) is None]
    if missing:
        raise InputError(f"the replay needs {', '.join(missing)} (or --calibration DIR --row N)")
    if args.db is not None:
        given = [f"--{k.replace('_', '-')}" for k in _TRANSFER_ONLY if getattr(args, k) is not None]
        if given:
            raise InputError(f"{', '.join(given)}: a study row's experiment comes from its "
                             "plan (leave out --db for a transfer's arguments)")  # fmt: skip
        if args.run is None:
            raise InputError("--db needs --run (the repetition index r of the row)")
        found = study_spec(args.db, args.object, args.face, args.conveyor, args.theta, args.run)
        return found.spec, found
    if args.run is not None:
        raise InputError("--run needs --db (a row of a study store)")
    spec = transfer_spec(
        args.object, args.face, args.conveyor, args.theta,
        seed=0 if args.seed is None else args.seed, dock_error=args.dock_error or "0,0,0",
        units=args.units, profile=args.profile, gap_mm=args.gap_mm, mu=args.mu,
    )  # fmt: skip
    return spec, None


def cmd_replay(args: argparse.Namespace) -> int:
    """Record the experiment, write the files asked for, then serve the 3-D view."""
    from transfertwin.cli._transfer import hull_notice
    from transfertwin.replay import (
        CalibrationRow,
        calibration_source,
        compare_with_row,
        record_experiment,
        replay_payload,
    )

    outputs = {
        "json": out_file(args.json, (".json",)) if args.json else None,
        "glb": out_file(args.glb, (".glb",)) if args.glb else None,
        "gif": out_file(args.gif, (".gif",)) if args.gif else None,
        "mp4": out_file(args.mp4, (".mp4",)) if args.mp4 else None,
    }
    if args.port is not None and not 0 <= args.port <= 65535:
        raise InputError(f"--port must be in 0..65535, got {args.port}")
    if args.gif or args.mp4:
        from transfertwin.replay import gif_frame_times

        gif_frame_times(1.0, args.fps, args.speed)  # bad --fps or --speed: before the run
    if args.plant_rows is not None:
        doc, replay = _plant_replay(args)
        return _write(args, outputs, doc, replay)
    spec, found = _spec(args)
    notice = hull_notice(spec.object_ref, spec.units)
    if notice:
        print(notice, file=sys.stderr, flush=True)
    replay = record_experiment(spec)
    source: dict[str, object] = {"kind": "transfer"}
    if isinstance(found, CalibrationRow):
        name = Path(args.calibration).resolve().name
        source = calibration_source(name, args.row, found, replay.result)
        print(f"calibration row {args.row}, run {found.spec.run}: really "
              f"{_word(found.real_success)}, the calibration's run {_word(found.predicted)}, "
              f"this replay {_word(source['replayed'])} ({found.note})",
              file=sys.stderr)  # fmt: skip
    elif found is not None:
        check = compare_with_row(replay.result, found.row) if found.row else None
        source = {"kind": "study", "study": found.store, "stored": found.row is not None,
                  "check": check, "runs": found.runs}  # fmt: skip
        if check is None:
            print(f"note: {found.store} has no row for this experiment yet", file=sys.stderr)
        elif not check["same"]:
            print("warning: the replay differs from the stored row: "
                  + "; ".join(check["differences"]), file=sys.stderr)  # fmt: skip
    print(replay_line(replay, same=bool(source.get("check")) and source["check"]["same"]),
          flush=True)  # fmt: skip
    doc = replay_payload(replay, source=source)
    return _write(args, outputs, doc, replay)


def _word(success: object) -> str:
    """A 0/1 outcome in words: 'delivered', 'failed', or 'not known' (None)."""
    return {1: "delivered", 0: "failed"}.get(success, "not known")  # type: ignore[call-overload]


def replay_line(replay, same: bool = False) -> str:
    """What `replay` prints of a virtual experiment: the experiment and its outcome in
    words, then what the replay shows (simulated time; the machine form is --json's)."""
    from transfertwin.replay import outcome_text, state_text

    row = replay.result.row()
    frames = f"{len(replay.t_s)} frames of {replay.duration_s:.2f} s simulated time"
    stored = "; the same result as the stored row" if same else ""
    return (f"{state_text(row)}, run {row['run']}, seed {row['seed']}: {outcome_text(row)}"
            f"{stored}. The replay shows {frames}.")  # fmt: skip


def _plant_replay(args: argparse.Namespace):  # -> (document, Replay)
    """A plant row's replay: its recording, drawn in the twin's scene (no hidden value)."""
    from transfertwin.replay import plant_source, record_plant, replay_payload

    found = _plant_row(args)
    replay = record_plant(found)
    row = replay.logged or {}
    outcome = "success" if row.get("success") == 1 else "failure"
    took = row.get("transfer_time_s")
    took_txt = f", transfer time {took:.3f} s" if isinstance(took, float) and took == took else ""
    title = (f"plant experiment {row.get('experiment_id')}: {row.get('object_id')} "
             f"{row.get('face')}, {row.get('conveyor')}, θ = {row.get('theta_deg')}°, "
             f"{row.get('transfer_unit')}")  # fmt: skip
    print(f"{found.table} row {found.index}, {title}: logged {outcome}{took_txt}; "
          f"{len(replay.t_s)} camera samples over {replay.duration_s:.2f} s ({found.note})",
          flush=True)  # fmt: skip
    return replay_payload(replay, source=plant_source(found, replay), title=title), replay


def _write(args: argparse.Namespace, outputs: dict, doc: dict[str, object], replay) -> int:
    """Write the files asked for; serve the view unless only files were asked for."""
    if outputs["json"] is not None:
        from transfertwin._atomic import write_atomic

        write_atomic(outputs["json"], json.dumps(doc, separators=(",", ":")))
        print(outputs["json"])
    if outputs["glb"] is not None:
        from transfertwin.replay import write_glb

        write_glb(replay, outputs["glb"])
        print(outputs["glb"])
    if outputs["gif"] is not None:
        from transfertwin.replay import write_gif

        write_gif(replay, outputs["gif"], fps=args.fps, speed=args.speed)
        print(outputs["gif"])
    if outputs["mp4"] is not None:
        from transfertwin.replay import write_mp4

        write_mp4(replay, outputs["mp4"], fps=args.fps, speed=args.speed)
        print(outputs["mp4"])
    if any(outputs.values()) and not args.serve:
        return 0
    return _serve(args, doc)


def _serve(args: argparse.Namespace, doc: dict[str, object]) -> int:
    from urllib.parse import urlsplit

    from transfertwin.web import WebConfig, serve

    config = WebConfig(dbs=(Path(args.db),) if args.db else (), host=args.host,
                       calibrations=(Path(args.calibration),) if args.calibration else (),
                       port=8765 if args.port is None else args.port)  # fmt: skip

    def ready(url: str) -> None:
        base = urlsplit(url)
        page = f"{base.scheme}://{base.netloc}/replay?key=cli&{base.query}"
        print(f"replay: {page}", flush=True)
        if not args.no_browser:
            webbrowser.open(page)

    serve(config, on_ready=ready, replays={"cli": doc})
    print("replay server down", flush=True)
    return 0


def register(sub: argparse._SubParsersAction) -> None:
    """Add `replay`."""
    p = sub.add_parser(
        "replay", help="re-simulate one experiment and show it in 3-D in the browser",
        description="Re-simulate one experiment deterministically (a study store's row with "
        "--db/--run, a calibration's row, or a transfer's arguments), or replay a plant "
        "experiment from its recording (--plant-rows/--row), and show it in 3-D in the "
        "browser (three.js, served locally), or write it as JSON, glTF (.glb, animated), GIF "
        "or MP4.",
    )  # fmt: skip
    p.add_argument("--db", help="study store (SQLite): replay its row (object, state, --run)")
    p.add_argument("--run", type=int, help="with --db: the row's repetition index r; with "
                   "--calibration: the calibration's run (default 0)")  # fmt: skip
    p.add_argument("--calibration", metavar="DIR",
                   help="a 'calibrate run' output folder: replay its real row --row")  # fmt: skip
    p.add_argument("--row", type=int, help="with --calibration: the real row's index; with "
                   "--plant-rows: the row's index in the table")  # fmt: skip
    p.add_argument("--plant-rows", metavar="CSV",
                   help="a plant's table (a rehearsal's plant_calibration.csv, plant_test.csv "
                   "or plant_validation.csv): replay its row --row from the plant's "
                   "recording")  # fmt: skip
    p.add_argument("--plant-seed", type=int, metavar="N",
                   help="with --plant-rows: the plant's seed (default: the plant.secret "
                   "beside the table or one folder up)")  # fmt: skip
    p.add_argument("--plant-seed-file", metavar="FILE",
                   help="with --plant-rows: a file holding the plant's seed (a plant floor's "
                   "plant.secret)")  # fmt: skip
    p.add_argument(
        "--plant-kind",
        metavar="KIND",
        help="with --plant-rows: in-class or mismatch (default: the rehearsal's; "
        "a bullet plant's rows cannot be replayed)",
    )
    p.add_argument("--object", help="object id (o1..o37) or a mesh path")
    p.add_argument("--units", default="m", help="length unit of a mesh file: m, cm, mm, in")
    p.add_argument("--face", help="front or back")
    p.add_argument("--conveyor", help="left, right or both")
    p.add_argument("--theta", type=int, help="yaw in integer degrees, -179..180")
    p.add_argument("--dock-error", help="without --db: X_MM,Y_MM,THETA_DEG (default 0,0,0)")
    p.add_argument("--seed", type=int, help="without --db: the experiment's seed (default 0)")
    p.add_argument("--profile", help="without --db: physics profile TOML or built-in name")
    p.add_argument("--mu", type=float, help="without --db: dynamic friction")
    p.add_argument("--gap-mm", type=float, help="without --db: nominal gap (mm)")
    p.add_argument("--json", help="write the replay document (what the page draws) here")
    p.add_argument("--glb", help="write an animated glTF binary (.glb) here")
    p.add_argument("--gif", help="write an animated GIF (MuJoCo's offscreen renderer) here")
    p.add_argument("--mp4", help="write an H.264 MP4 clip (the GIF's frames) here")
    p.add_argument("--fps", type=int, default=10,
                   help="GIF and MP4 frames per second (default 10)")  # fmt: skip
    p.add_argument(
        "--speed",
        type=float,
        default=2.0,
        help="GIF and MP4 playback speed, simulated s per second (default 2)",
    )
    p.add_argument("--serve", action="store_true", help="serve the 3-D view after writing files")
    p.add_argument("--no-browser", action="store_true", help="print the URL, open no browser")
    p.add_argument("--host", default="127.0.0.1", help="interface to serve on (loopback)")
    p.add_argument("--port", type=int, help="TCP port (default 8765; 0: any free port)")
    p.set_defaults(func=cmd_replay)
