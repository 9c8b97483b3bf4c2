"""`transfertwin calibrate run|sweep|tune|sensitivity|...`: virtual calibration against real
experiments."""

from __future__ import annotations

import argparse
import json
import math
import sys
from pathlib import Path

from rich.console import Console

from transfertwin._atomic import write_atomic
from transfertwin._errors import InputError
from transfertwin.cli._calibrate_out import (
    best_line,
    builtin_real,
    csv_text,
    json_safe,
    mapping_line,
    metric_line,
    prediction_rows,
    print_sensitivity,
    trial_line,
    undefined_reason,
    write_trials,
)
from transfertwin.cli._common import (
    add_executor_args,
    parse_positions,
    positive_int,
    with_executor,
    worker_count,
)
from transfertwin.cli._paths import out_dir
from transfertwin.cli._progress import progress_bar

__all__ = ["register"]

_DEFAULT_REAL = "builtin:calibration_experiments.csv"


def _real_rows(path: str) -> list[dict[str, object]]:
    from transfertwin.data import calibration_csv_path
    from transfertwin.store import read_results

    return read_results(calibration_csv_path() if path == _DEFAULT_REAL else path)


def _common(args: argparse.Namespace):
    """(rows, base scene, profile name, calibrate kwargs) from shared options."""
    from transfertwin.sim import SceneConfig
    from transfertwin.study.calibration import check_real_rows, parse_object_map
    from transfertwin.study.experiment import load_profile

    rows = _real_rows(args.real)
    check_real_rows(rows, args.real)
    if args.limit:
        rows = rows[: args.limit]
    name, scene = load_profile(args.profile) if args.profile else ("default", SceneConfig())
    ids = sorted({str(r["object_id"]) for r in rows})
    mapping = parse_object_map(args.object_map, ids)
    workers = worker_count(args.workers)
    calib = {"runs": args.runs, "object_map": mapping, "seed": args.seed, "workers": workers,
             "units": args.units, "executor": getattr(args, "started_executor", None)}  # fmt: skip
    return rows, scene, name, calib


def cmd_run(args: argparse.Namespace) -> int:
    """Replay the real experiments R times; write metrics.json and predictions.csv."""
    from transfertwin.study.calibration import calibrate

    rows, scene, name, calib = _common(args)
    out = out_dir(args.out)
    result = calibrate(rows, scene=scene, **calib)
    metrics = result.summary()["metrics"]
    confusions = [r.confusion for r in result.runs]
    shipped = args.real == _DEFAULT_REAL or builtin_real(rows)
    per_run = [
        {"run": r.run, **r.confusion.to_dict(), "not_ok": r.not_ok,
         **{k: r.confusion.metric(k) for k in metrics}}
        for r in result.runs
    ]  # fmt: skip
    undefined = {k: undefined_reason(confusions[0], k) for k in ("f05", "precision", "recall")
                 if all(undefined_reason(c, k) for c in confusions)}  # fmt: skip
    payload = {
        "profile": name, "real": args.real, "n_real": len(rows), "runs": per_run,
        "mean": {k: v["mean"] for k, v in metrics.items()},
        "std": {k: v["std"] for k, v in metrics.items()}, "std_ddof": 1,
        "undefined": undefined,
        "object_map": result.object_map,
        "note": "real objects are replayed with the mapped meshes; the real scans are not public"
        if shipped else "objects are replayed with the mapped meshes; a metric listed "
        "under 'undefined' has an empty denominator in every run (its mean is 0 by convention)",
    }  # fmt: skip
    write_atomic(out / "metrics.json", json.dumps(json_safe(payload), indent=2) + "\n")
    write_atomic(out / "predictions.csv", csv_text(prediction_rows(rows, result)))
    print(mapping_line(result.object_map, shipped))
    for key in ("f05", "precision", "recall", "accuracy"):
        print(metric_line(key, metrics, confusions))
    print(out / "metrics.json")
    return 0


def _parse_values(text: str) -> list[object]:
    values: list[object] = []
    for part in text.split(","):
        part = part.strip()
        if not part:
            continue
        try:
            values.append(int(part) if part.lstrip("-").isdigit() else float(part))
        except ValueError:
            values.append(True if part == "true" else False if part == "false" else part)
    if not values:
        raise InputError("--values is empty")
    return values


def _check_metric(metric: str) -> None:
    from transfertwin.study.calibration import METRICS

    if metric not in METRICS:
        raise InputError(f"unknown metric {metric!r}: choose one of {', '.join(METRICS)}")


def _records(trials) -> list:
    from transfertwin.study.calibration import tuned_trial

    return [(t.label, tuned_trial(i, t)) for i, t in enumerate(trials)]


def _keys(trials) -> list[str]:
    return sorted({k for t in trials for k in t.params})


def cmd_sweep(args: argparse.Namespace) -> int:
    """One-at-a-time sweep of one setting."""
    from transfertwin.study.calibration import best_trial, sweep

    _check_metric(args.metric)
    rows, scene, _, calib = _common(args)
    out = out_dir(args.out)
    trials = sweep(rows, args.param, _parse_values(args.values), base=scene, metric=args.metric,
                   on_trial=lambda t: print(trial_line(t.label, t.params, t.metric, t.score)),
                   **calib)  # fmt: skip
    write_trials(out, _records(trials), _keys(trials), args.metric, f"sweep of {args.param}")
    best = best_trial(trials)
    print(f"best: {trial_line(best.label, best.params, best.metric, best.score)}; "
          f"{out / 'trials.csv'}")  # fmt: skip
    return 0


def _space_text(args: argparse.Namespace) -> str:
    """--space, or the μ/gap box of the shorthand options (which may not repeat --space)."""
    from transfertwin.study.calibration import default_space

    mu = (0.2 if args.mu_min is None else args.mu_min, 0.8 if args.mu_max is None else args.mu_max)
    gap = (5.0 if args.gap_min_mm is None else args.gap_min_mm,
           40.0 if args.gap_max_mm is None else args.gap_max_mm)  # fmt: skip
    if not args.space:
        return default_space(mu, gap)
    given_mu = args.mu_min is not None or args.mu_max is not None
    given_gap = args.gap_min_mm is not None or args.gap_max_mm is not None
    names = {part.partition("=")[0].strip() for part in args.space.split(",")}
    if (given_mu and "mu" in names) or (given_gap and names & {"gap_mm", "gap_m"}):
        raise InputError("give a parameter's bounds either in --space or as --mu-*/--gap-*-mm")
    extra = (([f"mu={mu[0]!r}:{mu[1]!r}"] if given_mu else [])
             + ([f"gap_mm={gap[0]!r}:{gap[1]!r}"] if given_gap else []))  # fmt: skip
    return ",".join([args.space, *extra])


def _check_object_dims(space, rows) -> None:
    present = {(str(r["object_id"]), str(r["face"])) for r in rows}
    for d in space.object_dims():
        if d.object_face not in present:
            oid, face = d.object_face
            raise InputError(f"--space: {d.name}: the real rows hold no {oid} on face {face}")
    objects = {oid for oid, _ in present}
    for d in space.shift_dims():
        if d.shifted_object not in objects:
            raise InputError(f"--space: {d.name}: the real rows hold no {d.shifted_object}")


def cmd_tune(args: argparse.Namespace) -> int:
    """Tune a joint space of scene settings and proxy depths by TPE (resumable, RDB storage)
    or Latin hypercube rounds; save the best trial as a profile and its proxies."""
    from transfertwin.cli._paths import out_file
    from transfertwin.objects import write_proxy
    from transfertwin.study.calibration import (
        best_trial,
        open_storage,
        parse_space,
        scene_with,
        trial_proxies,
        tune_lhs,
        tune_tpe,
        tuned_trial,
    )
    from transfertwin.study.experiment import save_profile

    _check_metric(args.metric)
    positive_int("--trials", args.trials)
    if not (math.isfinite(args.penalty) and args.penalty >= 0):
        raise InputError(f"--penalty must be >= 0, got {args.penalty}")
    if args.method == "lhs" and (args.storage or args.study_name):
        raise InputError("--storage and --study-name are for --method tpe (lhs is not resumable)")
    if args.storage and "://" not in args.storage:
        raise InputError(f"--storage {args.storage!r}: expected an RDB URL such as sqlite:///t.db")
    rows, scene, _, calib = _common(args)
    space = parse_space(_space_text(args), scene)
    _check_object_dims(space, rows)
    out = out_dir(args.out)
    profile = out_file(args.save_profile, (".toml",)) if args.save_profile else None
    profile = profile or out / "profile.toml"
    if args.method == "tpe" and not args.storage:
        out.mkdir(parents=True, exist_ok=True)  # for the default sqlite storage
    storage = args.storage or f"sqlite:///{(out / 'tune.sqlite').resolve()}"
    if args.method == "tpe":
        open_storage(storage)
    work = out / "trials"
    metric = args.metric
    show = lambda t: print(f"{trial_line(f'T{t.number}', t.params, metric, t.metrics[metric])}"  # noqa: E731
                           f", objective {t.objective:.4f}")  # fmt: skip
    if args.method == "lhs":
        lhs = tune_lhs(rows, space, base=scene, n_per_round=args.trials, rounds=2,
                       metric=args.metric, penalty=args.penalty, work_dir=work,
                       on_trial=lambda t: print(trial_line(t.label, t.params, metric, t.score)),
                       **calib)  # fmt: skip
        records = [(t.label, tuned_trial(i, t)) for i, t in enumerate(lhs)]
        best = records[lhs.index(best_trial(lhs))][1]
        where = "latin hypercube (not stored)"
    else:
        with progress_bar("tune", Console(stderr=True)) as on_progress:
            study = tune_tpe(rows, space, base=scene, n_trials=args.trials, metric=args.metric,
                             penalty=args.penalty, storage=storage, study_name=args.study_name,
                             work_dir=work, on_trial=show, on_progress=on_progress,
                             **calib)  # fmt: skip
        records = [(f"T{t.number}", t) for t in study.trials]
        best = study.best()
        where = f"study {study.name} in {storage}"
        print(
            f"{where}: {len(study.trials)} complete trials ({study.added} added now"
            + (f", {study.stale} interrupted marked failed" if study.stale else "")
            + ")"
        )
    if work.is_dir() and not any(work.iterdir()):
        work.rmdir()
    write_trials(out, records, space.names(), args.metric,
                  f"calibrate tune ({args.method}, {args.metric})")  # fmt: skip
    mapping = dict(calib["object_map"])
    for oid, spec in trial_proxies(best.params, calib["object_map"]).items():
        mapping[oid] = str(write_proxy(spec, out / "objects" / f"{oid}.proxy.json"))
    object_map = ",".join(f"{k}={v}" for k, v in sorted(mapping.items()))
    label = next(lbl for lbl, t in records if t is best)
    comment = (f"calibrate tune: {where}, best trial {label}, {metric} "
               f"{best.metrics[metric]:.4f}\nreplay with --object-map {object_map}")  # fmt: skip
    save_profile(profile, args.name, scene_with(scene, best.params), comment)
    baseline = _baseline(rows, scene, metric, calib)
    payload = {
        "method": args.method, "study": where, "trial": label, "params": best.params,
        "objective": best.objective, "metric": args.metric, "metrics": best.metrics,
        "baseline": {metric: baseline, "note": "the starting profile with the unmodified "
                     "cores (no tuned setting, no proxy), same rows, runs and seed"},
        "penalty": best.penalty, "space": space.text(), "profile": str(profile),
        "object_map": object_map, "n_trials": len(records),
        "note": "tuned proxies are calibrated stand-ins, not scans; use the object map with "
                "the profile (--profile, --object-map)",
    }  # fmt: skip
    write_atomic(out / "best.json", json.dumps(json_safe(payload), indent=2) + "\n")
    print(f"{best_line(label, best.params, metric, best.metrics[metric], baseline)}; "
          f"profile {profile}; object map {object_map}")  # fmt: skip
    return 0


def _baseline(rows, scene, metric: str, calib: dict) -> float:
    """The untuned baseline: the metric of the starting profile with the unmodified cores
    (one more replay of the same rows, runs and seed)."""
    from transfertwin.study.calibration import Trial, replay_trial

    print(f"untuned baseline: replaying {len(rows)} rows x {calib['runs']} runs",
          file=sys.stderr, flush=True)  # fmt: skip
    return Trial("baseline", {}, replay_trial(rows, scene, {}, **calib), metric).score


def cmd_simstudy(args: argparse.Namespace) -> int:
    """Simulation-parameter study: each set of SIM_PARAMETER_SETS, R runs; the best set is
    recorded and saved as a profile."""
    from transfertwin.study.calibration import (
        SIM_PARAMETER_SETS,
        best_trial,
        scene_with,
        simulation_parameter_study,
    )
    from transfertwin.study.experiment import save_profile

    _check_metric(args.metric)
    rows, scene, _, calib = _common(args)
    sets = SIM_PARAMETER_SETS
    if args.sets:
        wanted = {s.strip() for s in args.sets.split(",")}
        unknown = wanted - {label for label, _ in sets}
        if unknown:
            raise InputError(f"unknown parameter set(s): {', '.join(sorted(unknown))}")
        sets = tuple(s for s in sets if s[0] in wanted)
    out = out_dir(args.out)
    trials = simulation_parameter_study(
        rows, base=scene, sets=sets, metric=args.metric,
        on_trial=lambda t: print(trial_line(t.label, t.params, t.metric, t.score)), **calib,
    )  # fmt: skip
    write_trials(out, _records(trials), _keys(trials), args.metric, "simulation-parameter study")
    best = best_trial(trials)
    chosen = {"label": best.label, "params": best.params, args.metric: best.score}
    write_atomic(out / "chosen.json", json.dumps(chosen, indent=2) + "\n")
    save_profile(out / "profile.toml", f"simstudy-{best.label}", scene_with(scene, best.params))
    print(f"chosen: {trial_line(best.label, best.params, best.metric, best.score)}; "
          f"{out / 'profile.toml'}")  # fmt: skip
    return 0


def _penalty_grid(text: str) -> tuple[float, ...]:
    try:
        values = tuple(float(v) for v in text.split(",") if v.strip())
    except ValueError:
        values = ()
    if not values or not all(math.isfinite(v) and v >= 0 for v in values):
        raise InputError(f"--penalties expects values >= 0 like 0,0.02,0.05, got {text!r}")
    return values


def _check_nested(args: argparse.Namespace) -> tuple[float, ...]:
    if args.folds < 2:
        raise InputError(f"--folds must be at least 2, got {args.folds}")
    positive_int("--repeats", args.repeats)
    positive_int("--cv-seeds", args.cv_seeds)
    positive_int("--resamples", args.resamples)
    if args.inner_folds < 2:
        raise InputError(f"--inner-folds must be at least 2, got {args.inner_folds}")
    _check_penalties(args)
    return _penalty_grid(args.penalties)


def cmd_evaluate(args: argparse.Namespace) -> int:
    """The honest headline: nested CV over --cv-seeds seeds of the twin (choosing among the
    candidate folders of --objects inside the training folds) beside rate tables, logistic
    regression and always-success; near-repeat noise ceiling; held-out cells; raw shares.
    Also the single-folder 5 x 5 figures of before. Writes evaluation.json, fidelity.json
    and fidelity.png."""
    import numpy as np

    from transfertwin.report import fidelity_plot_data, figure_png, plot_fidelity
    from transfertwin.study.calibration import (
        Variant,
        calibrate,
        evaluate_predictions,
        fidelity_report,
        fitted_candidates,
        report_lines,
    )

    penalties = _check_nested(args)
    rows, scene, name, calib = _common(args)
    objects = np.array([str(r["object_id"]) for r in rows])
    variants = []
    if args.objects:
        folders = [Path(f) for f in args.objects.split(",") if f.strip()]
        for folder in folders:
            if not folder.is_dir():
                raise InputError(f"--objects: {folder} is not a folder")
            candidates, groups = fitted_candidates(folder, rows)
            variants.append(Variant(folder.name, candidates, groups))
        runs = None
    else:
        result = calibrate(rows, scene=scene, **calib)
        p = result.probabilities()
        variants.append(Variant(f"profile {name}", {o: p[None, :] for o in sorted(set(objects))},
                                objects))  # fmt: skip
        runs = len(result.runs)
    out = out_dir(args.out)
    with progress_bar("nested CV", Console(stderr=True), unit="fold") as on_progress:
        report = fidelity_report(rows, variants, folds=args.folds, seeds=args.cv_seeds,
                                 seed=args.seed, inner_folds=args.inner_folds,
                                 penalties=penalties, shift_penalty=args.mass_penalty,
                                 position_penalty=args.position_penalty,
                                 n_resamples=args.resamples, on_progress=on_progress)  # fmt: skip
    first = variants[0]
    ev = evaluate_predictions(rows, first.candidates, folds=args.folds, repeats=args.repeats,
                              seed=args.seed, penalty=args.penalty, groups=first.groups,
                              shift_penalty=args.mass_penalty,
                              position_penalty=args.position_penalty)  # fmt: skip
    y = np.array([int(r["success"]) for r in rows])
    r = runs or 1
    sim = {o: (round(float(ev.twin_p[objects == o].sum()) * r), int((objects == o).sum()) * r)
           for o in sorted(set(objects))}  # fmt: skip
    held_out = {"twin (held out)": ev.twin_oof, "logistic (held out)": ev.logistic_oof}
    plot = fidelity_plot_data(y, held_out, objects, sim)
    payload = {
        "profile": name, "real": args.real, "n_real": ev.n, "real_successes": ev.successes,
        "runs": runs, "objects": args.objects, "chosen": ev.chosen, "folds": ev.folds,
        "repeats": ev.repeats, "seed": args.seed,
        **ev.figures, "per_object": ev.per_object,
        "nested": report,
        "note": "headline: 'nested' (fidelity.json): every choice inside the training "
                "folds over many CV seeds. The other figures are of the first candidate "
                f"folder ({first.label}) only, 5-fold x repeats with its penalty fixed; "
                "logistic: one-hot state, sin/cos of theta and 2 theta per object and face, "
                "docking error; hybrid (reported beside the twin, not instead): a logistic "
                "regression on the twin's P_sim and the logistic features, fitted in the "
                "training folds",
    }  # fmt: skip
    write_atomic(out / "fidelity.png", figure_png(plot_fidelity(plot)))
    write_atomic(out / "fidelity.json", json.dumps(json_safe(report), indent=2) + "\n")
    write_atomic(out / "evaluation.json", json.dumps(json_safe(payload), indent=2) + "\n")
    print("\n".join(report_lines(report)))
    print(f"single folder {first.label} ({args.folds}-fold x {args.repeats}, penalty "
          f"{args.penalty:g} fixed; not the headline):")  # fmt: skip
    for key in ("base_rate", "logistic_cv", "twin_in_sample", "twin_cv", "hybrid_cv"):
        f = ev.figures[key]
        print(f"  {key:15s} f05 {f['f05']:.3f}  precision {f['precision']:.3f}  "
              f"recall {f['recall']:.3f}  brier {f['brier']:.3f}")  # fmt: skip
    print(out / "fidelity.json")
    return 0


def _check_penalties(args: argparse.Namespace) -> None:
    for name, value in (("--penalty", args.penalty), ("--mass-penalty", args.mass_penalty),
                        ("--position-penalty", args.position_penalty)):  # fmt: skip
        if not (math.isfinite(value) and value >= 0):
            raise InputError(f"{name} must be >= 0, got {value}")


def cmd_object(args: argparse.Namespace) -> int:
    """Calibrate a proxy (shape and mass distribution) for one real object from its real
    outcomes (no scan needed)."""
    from transfertwin.objects import MAX_COM_SHIFT_M, write_proxy
    from transfertwin.study.calibration import (
        candidates_path,
        check_shifts,
        fit_proxy,
        save_candidates,
    )

    if args.family != "core":
        raise InputError(f"--family {args.family!r}: only 'core' (procedural cores) is known")
    depths = [float(v) / 1000 for v in _parse_values(args.depths_mm)]
    if any(d < 0 or d > 0.1 for d in depths):
        raise InputError("--depths-mm must lie in 0..100")
    shifts = [float(v) / 1000 for v in _parse_values(args.com_shifts_mm)]
    if any(not abs(v) <= MAX_COM_SHIFT_M for v in shifts):
        raise InputError(f"--com-shifts-mm must lie in ±{MAX_COM_SHIFT_M * 1000:g}")
    positions = parse_positions(args.positions)
    _check_penalties(args)
    positive_int("--runs", args.runs)
    rows, scene, _, calib = _common(args)
    if args.object not in {str(r["object_id"]) for r in rows}:
        raise InputError(f"{args.real}: no rows of object {args.object!r}")
    check_shifts(args.object, shifts)
    out = out_dir(args.out)
    with progress_bar(f"calibrate {args.object}", Console(stderr=True)) as on_progress:
        fit = fit_proxy(rows, args.object, depths_m=depths, work_dir=out / "candidates",
                        scene=scene, runs=args.runs, seed=args.seed, workers=calib["workers"],
                        penalty=args.penalty, shifts_m=shifts, shift_penalty=args.mass_penalty,
                        positions=positions, position_penalty=args.position_penalty,
                        on_progress=on_progress, executor=calib["executor"])  # fmt: skip
    proxy = write_proxy(fit.spec, out / f"{args.object}.proxy.json")
    save_candidates(fit, candidates_path(out, args.object))
    j = fit.shift_chosen
    for f in fit.faces:
        at_shift = f.probabilities[j]
        shares = ", ".join(f"{f.label(k)} {p.mean():.2f}" for k, p in enumerate(at_shift))
        print(
            f"{args.object} {f.face}: real {f.actual.mean():.2f} (n {len(f.actual)}); "
            f"simulated by depth: {shares}; chosen {f.label(f.chosen)}"
        )
    n = sum(len(f.actual) for f in fit.faces)
    by_shift = ", ".join(
        f"{s * 1000:+g} mm {sum(f.probabilities[i, f.chosen].sum() for f in fit.faces) / n:.2f}"
        for i, s in sorted(enumerate(fit.shifts_m), key=lambda t: t[1])
    )
    real = sum(f.actual.sum() for f in fit.faces) / n
    print(
        f"{args.object} mass: real {real:.2f}; simulated at the chosen depths by centre-of-mass "
        f"shift: {by_shift}; chosen {fit.spec.com_shift_m * 1000:+g} mm along x (front half "
        f"{fit.front_fraction:.0%} of the mass, uniform {fit.uniform_front_fraction:.0%})"
    )
    print(f"{proxy} (a calibrated proxy of shape and mass distribution, not a scan)")
    return 0


def cmd_sensitivity(args: argparse.Namespace) -> int:
    """One-at-a-time (or Morris) sensitivity of the replay to candidate gap mechanisms."""
    if getattr(args, "executor", "local") != "local":
        raise InputError("calibrate sensitivity runs on local worker processes (no --executor)")

    from transfertwin.report import (
        figure_png,
        morris_plot_data,
        plot_morris,
        plot_sensitivity,
        sensitivity_plot_data,
    )
    from transfertwin.study.calibration import morris_screening, one_at_a_time, parse_factors

    positive_int("--runs", args.runs)
    if args.levels is None:
        args.levels = 4 if args.method == "morris" else 3
    if args.levels < 2:
        raise InputError(f"--levels must be at least 2, got {args.levels}")
    if args.method == "morris" and (args.levels % 2 or args.trajectories < 2):
        raise InputError("--method morris needs an even --levels and --trajectories >= 2")
    rows, scene, name, calib = _common(args)
    calib.pop("executor", None)  # its scenes share one local pool (run_tagged)
    factors = parse_factors(args.params, scene)
    if args.method == "morris" and len(factors) < 2:
        raise InputError("--method morris needs at least two --params")
    out = out_dir(args.out)
    console = Console(width=None if sys.stdout.isatty() else 160)
    title = f"{args.method} sensitivity around '{name}' ({len(rows)} real rows, R {args.runs})"
    with progress_bar("sensitivity", Console(stderr=True)) as on_progress:
        if args.method == "morris":
            result = morris_screening(rows, base=scene, factors=factors, levels=args.levels,
                                      trajectories=args.trajectories, on_progress=on_progress,
                                      **calib)  # fmt: skip
        else:
            result = one_at_a_time(rows, base=scene, factors=factors, levels=args.levels,
                                   on_progress=on_progress, **calib)  # fmt: skip
    payload = {"profile": name, "real_table": args.real, **result.to_dict()}
    if args.method == "morris":
        fig = plot_morris(morris_plot_data(result), title)
    else:
        fig = plot_sensitivity(sensitivity_plot_data(result), title)
    write_atomic(out / "sensitivity.csv", csv_text(result.csv_rows()))
    write_atomic(out / "sensitivity.png", figure_png(fig))
    write_atomic(out / "sensitivity.json", json.dumps(json_safe(payload), indent=2) + "\n")
    print_sensitivity(result, args.method, title, console)
    print(out / "sensitivity.json")
    return 0


def _shared(p: argparse.ArgumentParser) -> None:
    p.add_argument("--real", default=_DEFAULT_REAL,
                   help="real result table (CSV/Parquet/db); default: the shipped 191")  # fmt: skip
    p.add_argument("--runs", type=int, default=3, help="repetitions R per real experiment")
    p.add_argument("--profile", help="physics profile TOML to start from")
    p.add_argument("--object-map", help="real id to mesh: o1=PATH,o18=o5 (default: same id)")
    p.add_argument("--units", default="m", help="length unit of mapped mesh files")
    p.add_argument("--workers", type=int, help="worker processes (default: all cores)")
    add_executor_args(p)
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--limit", type=int, default=0, help="use only the first N real rows")
    p.add_argument("--out", required=True, help="output directory")


def register(sub: argparse._SubParsersAction) -> None:
    """Add `calibrate run|sweep|tune` to the CLI."""
    cal = sub.add_parser("calibrate", help="virtual calibration against real experiments")
    csub = cal.add_subparsers(dest="calibrate_command", required=True, parser_class=type(cal))
    p = csub.add_parser("run", help="replay real experiments; metrics.json (F0.5 etc.)")
    _shared(p)
    p.set_defaults(func=with_executor(cmd_run))
    p = csub.add_parser("sweep", help="one-at-a-time sweep of a setting (Fig. 6.12/6.14)")
    _shared(p)
    p.add_argument("--param", required=True, help="mu, gap_mm, physics.solver, ...")
    p.add_argument("--values", required=True, help="comma-separated values")
    p.add_argument("--metric", default="f05")
    p.set_defaults(func=with_executor(cmd_sweep))
    p = csub.add_parser("simstudy", help="simulation-parameter study (Sec. 6.5.1, Fig. 6.12)")
    _shared(p)
    p.add_argument("--sets", help="labels to run, e.g. S0,S3,S5 (default: all)")
    p.add_argument("--metric", default="f05")
    p.set_defaults(func=with_executor(cmd_simstudy))
    p = csub.add_parser("object", help="calibrate a proxy object from real outcomes (no scan)")
    _shared(p)
    p.add_argument("--object", required=True, help="real object id, e.g. o1")
    p.add_argument("--family", default="core", help="shape family of the proxy (core)")
    p.add_argument("--depths-mm", default="6,10,14,18,20,22,24,26,28",
                   help="candidate protrusion depths below a face (0 is always tried)")  # fmt: skip
    p.add_argument("--penalty", type=float, default=0.02,
                   help="Brier penalty at the deepest candidate (towards the prior)")  # fmt: skip
    p.add_argument("--com-shifts-mm", default="-20,-10,10,20",
                   help="candidate centre-of-mass shifts along x (0, uniform, is always "
                   "tried; '0': do not search the mass distribution)")  # fmt: skip
    p.add_argument("--mass-penalty", type=float, default=0.02,
                   help="Brier penalty at the largest |centre-of-mass shift|")  # fmt: skip
    p.add_argument("--positions", default="0.5",
                   help="candidate protrusion positions along the object's x axis, fractions of "
                   "its length (e.g. 0.3,0.5,0.7; default 0.5: centred, not searched)")  # fmt: skip
    p.add_argument("--position-penalty", type=float, default=0.02,
                   help="Brier penalty at the position farthest from the centre")  # fmt: skip
    p.set_defaults(func=with_executor(cmd_object), runs=2)
    p = csub.add_parser("evaluate", help="twin vs baselines, in-sample and cross-validated")
    _shared(p)
    p.add_argument("--folds", type=int, default=5, help="stratified folds K (default 5)")
    p.add_argument("--repeats", type=int, default=5, help="repetitions of the K folds")
    p.add_argument("--objects", help="folder(s) of 'calibrate object' outputs, comma-"
                   "separated (scene variants): the folder, proxies, shrinkage and threshold "
                   "are chosen in the training folds (default: simulate --profile)")  # fmt: skip
    p.add_argument("--cv-seeds", type=int, default=20,
                   help="nested CV: stratified K-fold partitions, one per seed (default 20)")
    p.add_argument("--inner-folds", type=int, default=3,
                   help="nested CV: inner folds that choose folder and penalty (default 3)")
    p.add_argument("--penalties", default="0,0.02,0.05",
                   help="nested CV: depth penalties chosen from inside the training folds")
    p.add_argument("--resamples", type=int, default=2000,
                   help="bootstrap resamples of the 95%% intervals (default 2000)")
    p.add_argument("--penalty", type=float, default=0.02,
                   help="Brier penalty at the deepest proxy candidate (single-folder "
                   "figures)")  # fmt: skip
    p.add_argument("--mass-penalty", type=float, default=0.02,
                   help="Brier penalty at the largest centre-of-mass shift")  # fmt: skip
    p.add_argument("--position-penalty", type=float, default=0.02,
                   help="Brier penalty at the protrusion position farthest from the "
                   "centre")  # fmt: skip
    p.set_defaults(func=with_executor(cmd_evaluate))
    p = csub.add_parser("sensitivity", help="which gap mechanism changes the outcomes (OAT/Morris)")
    _shared(p)
    p.add_argument("--params", help="NAME=LO:HI,... (default: every candidate mechanism; "
                   "NAME a known factor or a float scene setting, e.g. t_max_s)")  # fmt: skip
    p.add_argument("--levels", type=int,
                   help="values per factor (default 3; Morris: even, default 4)")  # fmt: skip
    p.add_argument("--method", choices=("oat", "morris"), default="oat",
                   help="one-at-a-time around --profile (default) or Morris (SALib)")  # fmt: skip
    p.add_argument("--trajectories", type=int, default=4, help="Morris trajectories")
    p.set_defaults(func=cmd_sensitivity, runs=1)
    p = csub.add_parser("tune", help="tune scene settings and proxy depths jointly (TPE, "
                        "resumable; or LHS rounds); save the best as a profile")  # fmt: skip
    _shared(p)
    p.add_argument("--method", choices=("lhs", "tpe"), default="tpe")
    p.add_argument("--trials", type=int, default=12,
                   help="complete trials in the study (tpe; earlier runs count), or trials per "
                   "round (lhs)")  # fmt: skip
    p.add_argument("--space", help="NAME=LO:HI[:log],... e.g. mu=0.3:0.8,gap_mm=8:16,"
                   "layout.pulley_radius_m=0.01:0.025,physics.solref[0]=0.002:0.02:log,"
                   "object.o1.front_depth_mm=0:30 (default: mu and gap_mm)")  # fmt: skip
    p.add_argument("--mu-min", type=float, help="shorthand: mu=MIN:MAX (default 0.2:0.8)")
    p.add_argument("--mu-max", type=float)
    p.add_argument("--gap-min-mm", type=float, help="shorthand: gap_mm=MIN:MAX (default 5:40)")
    p.add_argument("--gap-max-mm", type=float)
    p.add_argument("--metric", default="f05",
                   help="objective: f05 (default, maximised) or brier (minimised; the Brier "
                   "score of P(success) per row over the runs)")  # fmt: skip
    p.add_argument("--penalty", type=float, default=0.02,
                   help="weight of the proxy-depth penalty towards the family prior")  # fmt: skip
    p.add_argument("--storage", help="optuna RDB URL (tpe; default sqlite:///OUT/tune.sqlite)")
    p.add_argument("--study-name", help="study name (default: derived from the settings)")
    p.add_argument("--name", default="calibrated", help="name of the saved profile")
    p.add_argument("--save-profile", help="profile path (default OUT/profile.toml)")
    p.set_defaults(func=with_executor(cmd_tune))
