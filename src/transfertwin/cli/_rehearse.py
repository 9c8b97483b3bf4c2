"""`transfertwin rehearse`: the whole calibrate → predict → validate loop on an emulated plant.

Writes ``rehearsal.json``, ``report.html`` and the plant's and twin's rows into ``--out``
and prints what it found (saying when the held-out rows are too few for a change in F0.5
to be significant) and where ``report.html`` is.
With several ``--calibration-experiments`` (``25,50,100``) each K gets ``--out/K<k>/``;
``--out/rehearsal.json`` (and ``curve.json``) collect F0.5 and the significant differences
against K, and ``--out/report.html`` plots them. ``--ablate mass|stability|compliance``
(repeatable or a comma list) adds twin variants with one counter-measure switched off;
``--operations N`` serves N orders with the twin's predictions and N with random placement;
``--test-experiments H`` scores F0.5 on H separate plant experiments (the same for every K).
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

from rich.console import Console

from transfertwin._atomic import write_atomic
from transfertwin._errors import InputError
from transfertwin.cli._common import parse_positions, worker_count
from transfertwin.cli._paths import out_dir
from transfertwin.cli._progress import progress_bar

__all__ = ["cmd_rehearse", "register"]


def _counts(text: str) -> tuple[int, ...]:
    try:
        ks = tuple(int(p) for p in text.split(",") if p.strip())
    except ValueError:
        ks = ()
    if not ks or any(k < 1 for k in ks) or len(set(ks)) != len(ks):
        raise InputError(
            f"--calibration-experiments expects K or distinct K1,K2,... >= 1, got {text!r}"
        )
    return ks


def _depths(text: str) -> tuple[float, ...]:
    try:
        return tuple(float(p) for p in text.split(",") if p.strip())
    except ValueError:
        raise InputError(f"--depths-mm expects D1,D2,... in mm, got {text!r}") from None


def _summary_line(doc: dict, n_objects: int, where: Path) -> str:
    """What one rehearsal found, with the small-n caveat of `f05_change_text`, and where
    its report is."""
    from transfertwin.report import REHEARSAL_REPORT_NAME, f05_change_text, rehearsal_plot_data

    k = doc["config"]["calibration_experiments"]
    return (
        f"K={k}: F0.5 on {doc['held_out']} held-out rows before {doc['f05_before']:.3f}, "
        f"after {doc['f05_after']:.3f} (always-success {doc['f05_base_rate']:.3f}); "
        f"{f05_change_text(rehearsal_plot_data(doc))}; significant best "
        f"{doc['significant_best']}/{n_objects}, worst {doc['significant_worst']}/{n_objects}; "
        f"{doc['plant_experiments']} plant and {doc['virtual_experiments']} virtual "
        f"experiments in {doc['seconds']} s\n  report: {where / REHEARSAL_REPORT_NAME} "
        "(rehearsal.json and the rows beside it)"
    )


def cmd_rehearse(args: argparse.Namespace) -> int:
    """Rehearse the study's procedure against an emulated plant."""
    from transfertwin.rehearsal import RehearsalConfig, curve_document, parse_object_list, rehearse
    from transfertwin.report import write_rehearsal_curve_report, write_rehearsal_report
    from transfertwin.sim import SceneConfig
    from transfertwin.study.experiment import load_profile

    ks = _counts(args.calibration_experiments)
    scene = load_profile(args.profile)[1] if args.profile else SceneConfig()
    configs = [
        RehearsalConfig(
            plant_seed=args.plant_seed, objects=parse_object_list(args.objects),
            calibration_experiments=k, runs=args.runs, validation_runs=args.validation_runs,
            theta_step=args.theta_step, holdout=args.holdout,
            test_experiments=args.test_experiments, depths_mm=_depths(args.depths_mm),
            proxy_positions=parse_positions(args.proxy_positions, "--proxy-positions"),
            tune_trials=args.tune_trials, object_prior=args.object_prior,
            min_face_rows=args.min_face_rows, seed=args.seed, workers=worker_count(args.workers),
            scene=scene, ablate=tuple(args.ablate or ()), operations=args.operations,
            plant_kind=args.plant_kind,
            mismatch_off=tuple(p.strip() for p in args.mismatch_off.split(",") if p.strip()),
        )
        for k in ks
    ]  # fmt: skip
    out = out_dir(args.out)
    console = Console(stderr=True)
    docs = []
    for cfg in configs:
        where = out if len(configs) == 1 else out / f"K{cfg.calibration_experiments}"
        with progress_bar("rehearse", console) as update:

            def stage(name: str) -> None:
                console.print(f"[bold]{name}")

            doc = rehearse(cfg, where, on_stage=stage, on_progress=update)
        write_rehearsal_report(doc, where)
        docs.append(doc)
        print(_summary_line(doc, len(cfg.objects), where))
        for m, ab in doc["ablations"].items():
            print(
                f"  without {m}: F0.5 after {ab['f05_after']:.3f} "
                f"({ab['delta_f05_after']:+.3f}), significant best {ab['significant_best']} "
                f"({ab['delta_significant_best']:+d}), worst {ab['significant_worst']} "
                f"({ab['delta_significant_worst']:+d})"
            )
        ops = doc["operations"]
        if ops:
            t, r = ops["twin"], ops["random"]
            print(
                f"  operations: success {t['k']}/{t['n']} with predictions vs {r['k']}/{r['n']} "
                f"random (diff {ops['success_diff']:+.2f}, 95 % CI [{ops['success_diff_low']:.2f},"
                f" {ops['success_diff_high']:.2f}]); {t['ops_per_hour']:.1f} vs "
                f"{r['ops_per_hour']:.1f} completed operations/h"
            )
    if len(configs) > 1:
        curve = curve_document(docs)
        write_atomic(out / "curve.json", json.dumps(curve["curve"], indent=2) + "\n")
        write_atomic(out / "rehearsal.json", json.dumps(curve, indent=2) + "\n")
        page = write_rehearsal_curve_report(curve, out)
        print(f"curve over K: {page} (curve.json, rehearsal.json beside it)")
    return 0


def register(sub: argparse._SubParsersAction) -> None:
    """Add `rehearse` to the CLI."""
    p = sub.add_parser("rehearse", help="calibrate, predict and validate against an emulated plant")
    p.add_argument(
        "--plant-seed",
        type=int,
        required=True,
        metavar="N",
        help="seed of the emulated plant (draws its hidden parameters)",
    )
    p.add_argument(
        "--plant-kind",
        default="in-class",
        metavar="KIND",
        help="in-class (default): a plant of the twin's own model class with hidden values; "
        "mismatch: structural differences the twin cannot represent (shape outside the proxy "
        "family, 3-D mass, belt ripple and skew, another contact model and solver); "
        "bullet: the in-class plant simulated in another physics engine, PyBullet",
    )
    p.add_argument(
        "--mismatch-off",
        default="",
        metavar="PART,...",
        help="with --plant-kind mismatch: parts of the mismatch switched off (shape, mass, "
        "belts, contact, appendage, compliant, sag), a rehearsal per ablated part",
    )
    p.add_argument("--objects", required=True, metavar="IDS", help="built-in cores, e.g. o3,o7")
    p.add_argument(
        "--calibration-experiments",
        required=True,
        metavar="K[,K2,...]",
        help="plant experiments for calibration; several give a curve",
    )
    p.add_argument("--out", required=True, metavar="DIR", help="output directory")
    p.add_argument(
        "--runs", type=int, default=2, help="replay repetitions and runs per state (default 2)"
    )
    p.add_argument(
        "--validation-runs",
        type=int,
        default=10,
        help="plant and virtual runs per best/worst state (default 10)",
    )
    p.add_argument(
        "--theta-step",
        type=int,
        default=90,
        help="θ grid of the full-state prediction, degrees (default 90)",
    )
    p.add_argument(
        "--holdout",
        type=float,
        default=0.3,
        help="share of the K experiments held out for F0.5 (default 0.3)",
    )
    p.add_argument(
        "--test-experiments",
        type=int,
        default=0,
        metavar="H",
        help="H extra plant experiments only for scoring F0.5 (then all K calibrate, and "
        "every K of a curve is scored on the same H); default 0: --holdout of the K",
    )
    p.add_argument(
        "--depths-mm",
        default="8,16,24,32",
        help="candidate protrusion depths of the object calibration (mm)",
    )
    p.add_argument(
        "--proxy-positions",
        default="0.5",
        metavar="X1,X2,...",
        help="candidate protrusion positions along the object's x axis searched with the "
        "depths, fractions of its length (e.g. 0.3,0.5,0.7; default 0.5: centred)",
    )
    p.add_argument(
        "--tune-trials",
        type=int,
        default=0,
        help="TPE trials over mu and gap after the object calibration (default 0)",
    )
    p.add_argument(
        "--object-prior",
        choices=("plain", "shipped"),
        default="plain",
        help="what object calibration moves from: the plain body (default, the study's) or "
        "each face's shipped feature",
    )
    p.add_argument(
        "--min-face-rows",
        type=int,
        default=1,
        help="training rows a face needs before its depth is searched; fewer: it keeps its "
        "prior (default 1)",
    )
    p.add_argument(
        "--ablate",
        action="append",
        metavar="MEASURE",
        help="switch one counter-measure off in an extra twin variant: mass, stability, "
        "compliance (repeatable or a comma list)",
    )
    p.add_argument(
        "--operations",
        type=int,
        default=0,
        metavar="N",
        help="serve N orders with the twin's predictions and N with random placement (default 0)",
    )
    p.add_argument("--profile", metavar="TOML", help="the twin's starting profile")
    p.add_argument("--seed", type=int, default=0, help="master seed of the twin's side")
    p.add_argument("--workers", type=int, default=None, help="worker processes (default: CPUs)")
    p.set_defaults(func=cmd_rehearse)  # fmt: skip
