"""`rehearse`: the study's whole procedure against an emulated plant.

1. K calibration experiments E^P on the plant at random states (the study's design: random
   face, conveyor and θ, objects in turn; or space-filling, `calibration_design`), split
   into training rows and held-out rows (stratified by object).
2. The twin before calibration (default scene, built-in cores with their shipped features)
   replays the held-out rows: ``f05_before``.
3. Virtual calibration on the training rows only: object calibration (`fit_proxy`, one
   protrusion depth per face) and, with ``tune_trials`` > 0, a TPE search over μ and the gap
   (`tune_tpe`) with the calibrated objects.
4. The calibrated twin replays the held-out rows: ``f05_after``.
5. Full-state prediction of every object on a θ grid, docking errors from a copula fitted
   to the plant's logged errors; best/worst state per object (Alg. 1–4).
6. Validation: V experiments on the plant and V virtual runs at each best/worst state;
   Newcombe hybrid score intervals of p_V − p_P (Sec. 6.7).

The twin's only inputs from the plant are the rows `EmulatedPlant.run` returns
(`PLANT_COLUMNS`, like the real calibration table). F0.5 is the mean over the R replay
runs of each run's F0.5 (the study's Table 6.4 definition, Appendix A.2; `_scoring`).
"""

from __future__ import annotations

import csv
import io
import json
import logging
import math
import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Protocol

import numpy as np

from transfertwin._atomic import write_atomic
from transfertwin._errors import InputError
from transfertwin.objects import PROXY_SUFFIX, ProxySpec, builtin_features, write_proxy
from transfertwin.ots import experiment_states, filter_theta_step
from transfertwin.plant import (
    PLANT_COLUMNS,
    PLANT_SEED_FILE,
    EmulatedPlant,
    PlantRequest,
    write_plant_seed,
)
from transfertwin.rehearsal._config import (
    COUNTER_MEASURES,
    RehearsalConfig,
    config_record,
    twin_scene,
)
from transfertwin.rehearsal._design import calibration_design, holdout_split
from transfertwin.rehearsal._operations import run_operations
from transfertwin.rehearsal._scoring import (
    base_rate_f05,
    f05_intervals,
    held_out_scores,
    run_predictions,
)
from transfertwin.rehearsal._thresholded import majority_scores, training_threshold
from transfertwin.sim import DockingError, SceneConfig
from transfertwin.store import DOCKING_ERROR_COLUMNS
from transfertwin.study.calibration import (
    CalibrationResult,
    calibrate,
    fit_proxy,
    parse_space,
    scene_with,
    tune_tpe,
)
from transfertwin.study.docking import (
    MIN_ROWS,
    GaussianCopula,
    ResampledDockingErrors,
    marginal_family,
)
from transfertwin.study.experiment import (
    ExperimentSpec,
    delivery_docking_seed,
    experiment_seeds,
    run_rows,
)
from transfertwin.study.fullstate import analyze
from transfertwin.study.validation import compare

__all__ = [
    "CURVE_KEYS",
    "REHEARSAL_KEYS",
    "curve_document",
    "rehearse",
]

log = logging.getLogger(__name__)

#: Keys every ``rehearsal.json`` has.
REHEARSAL_KEYS = (
    "f05_before", "f05_after", "significant_best", "significant_worst", "objects",
    "plant_experiments", "virtual_experiments",
)  # fmt: skip


#: What `--tune-trials` searches (TPE, `tune_tpe`) once the objects are calibrated: the
#: scene's friction and the gap between the docked belts.
TUNED_SPACE = "mu=0.3:0.7,gap_mm=8.0:18.0"


#: Marginal families of the twin's docking model (fast; see `transfertwin.plant`).
_FAMILIES = ("normal", "truncnorm", "kde")

Stage = Callable[[str], None]
Progress = Callable[[int, int], None]


def _csv_text(rows: Sequence[Mapping[str, object]], columns: Sequence[str]) -> str:
    buf = io.StringIO()
    writer = csv.DictWriter(buf, columns, lineterminator="\n", extrasaction="ignore")
    writer.writeheader()
    writer.writerows(rows)
    return buf.getvalue()


def _docking_model(rows: Sequence[Mapping[str, object]]):
    """The twin's docking-error model: a copula fitted to the plant's logged errors, or
    those errors resampled when there are fewer than `MIN_ROWS`."""
    errors = np.array([[float(r[c]) for c in DOCKING_ERROR_COLUMNS] for r in rows])
    if len(errors) >= MIN_ROWS:
        try:
            return GaussianCopula.fit(errors, families=[marginal_family(f) for f in _FAMILIES])
        except InputError:
            log.warning("copula fit failed on %d plant errors; resampling them", len(errors))
    return ResampledDockingErrors(tuple(tuple(map(float, e)) for e in errors), "plant")


def _state_grid(step: int) -> list[tuple[str, str, int]]:
    return [s.key for s in filter_theta_step(experiment_states(), step)]


def _virtual_specs(
    object_map: Mapping[str, str], states: Sequence[tuple[str, str, str, int]], runs: int,
    docking, scene: SceneConfig, seed: int, leg: str = "round-trip",
) -> list[ExperimentSpec]:  # fmt: skip
    """The E^V of `states`, `runs` each; an 'operation' leg docks at its destination with a
    docking error of its own (`delivery_docking_seed`, as `StudyPlan` draws it)."""
    specs = []
    for i, (oid, face, conveyor, theta) in enumerate(states):
        for run in range(runs):
            exp_seed, dock_seed = experiment_seeds(seed, oid, i, run)
            delivery = None
            if leg == "operation":
                delivery = docking.sample(delivery_docking_seed(seed, oid, i, run))
            specs.append(ExperimentSpec(
                object_map[oid], face, conveyor, theta, docking_error=docking.sample(dock_seed),
                scene=scene, run=run, seed=exp_seed, leg=leg, delivery_docking_error=delivery,
            ))  # fmt: skip
    return specs


@dataclass
class _Run:
    """What one rehearsal shares between its twin variants."""

    cfg: RehearsalConfig
    plant: Plant
    plant_rows: list[dict[str, object]]
    train: list[Mapping[str, object]]
    test: list[Mapping[str, object]]
    stage: Stage
    progress: Progress
    leg: str = "round-trip"
    virtual: int = 0
    plant_validation: int = 0

    @property
    def calib(self) -> dict[str, int]:
        return {"runs": self.cfg.runs, "seed": self.cfg.seed, "workers": self.cfg.workers}

    def replay(self, rows, scene: SceneConfig, object_map=None) -> CalibrationResult:
        total, done = len(rows) * self.cfg.runs, [0]

        def tick() -> None:
            done[0] += 1
            self.progress(done[0], total)

        self.virtual += total
        return calibrate(rows, scene=scene, object_map=object_map, on_result=tick, **self.calib)


def _calibrate_objects(
    run: _Run, measures: frozenset[str], scene: SceneConfig, out: Path
) -> tuple[dict[str, str], dict[str, dict[str, object]]]:
    """Object calibration of every object: (object map, what was fitted per object)."""
    cfg, obj_dir = run.cfg, out / "objects"
    object_map: dict[str, str] = {}
    fits: dict[str, dict[str, object]] = {}
    for oid in cfg.objects:
        fit_info: dict[str, object] = {}
        base, mass = None, None
        if "mass" in measures:  # the counter-measure: weigh and balance the part
            mass = run.plant.weigh(oid)
            fit_info["measured_mass_kg"] = mass.mass_kg
            fit_info["measured_com_mm"] = [round(v * 1000, 1) for v in mass.com_m]
            spec = ProxySpec(oid, oid, (), note="measured mass, plain body",
                             mass_kg=mass.mass_kg, com_m=mass.com_m)  # fmt: skip
            base = str(write_proxy(spec, obj_dir / f"{oid}.mass{PROXY_SUFFIX}").resolve())
        if not any(r["object_id"] == oid for r in run.train):
            object_map[oid] = base or oid
            fits[oid] = {"calibrated": False, "reason": "no training rows", **fit_info}
            continue
        run.stage(f"object calibration of {oid}")
        fit = fit_proxy(
            run.train, oid, depths_m=[d / 1000 for d in cfg.depths_mm], base=base,
            positions=cfg.proxy_positions, work_dir=obj_dir / "candidates", scene=scene,
            on_progress=run.progress, min_rows=cfg.min_face_rows,
            prior=builtin_features(oid) if cfg.object_prior == "shipped" else (), **run.calib,
        )  # fmt: skip
        run.virtual += sum(f.probabilities.size for f in fit.faces) * cfg.runs
        spec = ProxySpec(oid, oid, fit.spec.protrusions,
                         mass_kg=mass.mass_kg if mass else None,
                         com_m=mass.com_m if mass else None)  # fmt: skip
        path = write_proxy(spec, obj_dir / f"{oid}{PROXY_SUFFIX}")
        object_map[oid] = str(path)
        fits[oid] = {
            "calibrated": True,
            "proxy": str(path.relative_to(out)),
            "depth_mm": {p.face: round(p.depth_m * 1000, 3) for p in fit.spec.protrusions},
            **fit_info,
        }
        if cfg.object_prior != "plain" or cfg.min_face_rows != 1:  # which faces moved
            fits[oid]["faces_searched"] = [f.face for f in fit.faces]
        if set(cfg.proxy_positions) != {0.5}:  # searched: where along x (0.5 the centre)
            fits[oid]["x_frac"] = {p.face: p.x_frac for p in fit.spec.protrusions}
    return object_map, fits


def _adaptive_fullstate(run: _Run, object_map: Mapping[str, str], docking,
                        scene: SceneConfig) -> list[dict[str, object]]:  # fmt: skip
    """The full-state prediction as the floor's on-the-fly one makes it (Alg. 1–4 with the
    study's adaptive sampling): the budget of `runs` runs a state in all, a first round on
    every state, then rounds on each object's leaders and challengers, up to
    `ADAPTIVE_MAX_FACTOR` × `runs` on a state (`adaptive_options`, the settings of the
    floor's on-the-fly predictions); rows with the calibrated objects' ids."""
    from transfertwin.store import MemoryResultStore
    from transfertwin.study.adaptive import ADAPTIVE_MAX_FACTOR, adaptive_options, run_adaptive
    from transfertwin.study.experiment import StudyPlan

    cfg = run.cfg
    refs = {oid: object_map[oid] for oid in cfg.objects}
    plan = StudyPlan(tuple(refs.values()), cfg.theta_step, ADAPTIVE_MAX_FACTOR * cfg.runs,
                     cfg.seed, docking, scene=scene, leg=run.leg, sampling="adaptive",
                     sampling_options=adaptive_options(cfg.runs))  # fmt: skip
    store = MemoryResultStore()
    budget = len(plan.states()) * len(refs) * cfg.runs
    run_adaptive(plan, store, workers=cfg.workers, max_experiments=budget,
                 on_progress=run.progress)  # fmt: skip
    back = {ref: oid for oid, ref in refs.items()}
    rows = [dict(r) for r in store.rows()]
    for r in rows:  # the store names an object by its reference (a proxy's file)
        r["object_id"] = back.get(str(r["object_id"]), r["object_id"])
    return rows


def _twin(run: _Run, measures: frozenset[str], out: Path) -> dict[str, object]:
    """Calibrate, predict and validate one twin variant (`measures` switched on); writes its
    rows and proxies into `out` and returns its part of ``rehearsal.json`` (and, under
    private keys, its rows)."""
    cfg = run.cfg
    out.mkdir(parents=True, exist_ok=True)
    virtual0 = run.virtual
    scene = twin_scene(cfg.scene, measures)
    object_map, fits = _calibrate_objects(run, measures, scene, out)

    tuned = None
    if cfg.tune_trials:
        run.stage(f"scene tuning: {cfg.tune_trials} TPE trials over mu and gap")
        study = tune_tpe(
            run.train, parse_space(TUNED_SPACE, scene), base=scene,
            n_trials=cfg.tune_trials, object_map=object_map, **run.calib,
        )  # fmt: skip
        run.virtual += cfg.tune_trials * len(run.train) * cfg.runs
        best = study.best()
        scene = scene_with(scene, best.params)
        tuned = {**best.params, "f05": best.metrics["f05"]}

    run.stage("calibrated twin: replay of the held-out experiments")
    after_result = run.replay(run.test, scene, object_map)
    after = held_out_scores(after_result)

    run.stage(f"full-state prediction ({cfg.fullstate_sampling})")
    docking = _docking_model(run.plant_rows)
    if cfg.fullstate_sampling == "adaptive":
        full_rows = _adaptive_fullstate(run, object_map, docking, scene)
    else:
        grid = [(o, *s) for o in cfg.objects for s in _state_grid(cfg.theta_step)]
        specs = _virtual_specs(object_map, grid, cfg.runs, docking, scene, cfg.seed, run.leg)
        full_rows = _collect(run_rows(specs, cfg.workers), len(specs), run.progress)
    run.virtual += len(full_rows)
    analysis = analyze(full_rows)

    run.stage(f"validation: {cfg.validation_runs} plant and virtual runs per best/worst state")
    chosen: list[tuple[str, str, str, int]] = []
    picks: dict[str, dict[str, tuple[str, str, str, int]]] = {}
    for sel in analysis.selections:
        picks[sel.object_id] = {}
        for kind, st in (("best", sel.best), ("worst", sel.worst)):
            key = (sel.object_id, st.face, st.conveyor, st.theta_deg)
            picks[sel.object_id][kind] = key
            if key not in chosen:
                chosen.append(key)
    val_requests = [PlantRequest(*k) for k in chosen for _ in range(cfg.validation_runs)]
    plant_val = run.plant.run(val_requests, workers=cfg.workers, on_progress=run.progress)
    run.plant_validation += len(plant_val)
    vspecs = _virtual_specs(object_map, chosen, cfg.validation_runs, docking, scene, cfg.seed + 1)
    virtual_val = _collect(run_rows(vspecs, cfg.workers), len(vspecs), run.progress)
    run.virtual += len(vspecs)
    by_state = {c.key: c for c in compare(virtual_val, plant_val)}

    objects: dict[str, object] = {}
    significant: dict[str, list[str]] = {"best": [], "worst": []}
    for oid in cfg.objects:
        entry: dict[str, object] = {"calibration": fits[oid]}
        for kind, key in picks.get(oid, {}).items():
            c = by_state.get(key)
            if c is None:
                continue
            entry[kind] = {
                "face": key[1], "conveyor": key[2], "theta_deg": key[3],
                "n_v": c.n_v, "k_v": c.k_v, "p_v": c.p_v, "n_p": c.n_p, "k_p": c.k_p,
                "p_p": c.p_p, "diff_low": c.diff_low, "diff_high": c.diff_high,
                "significant": c.significant,
            }  # fmt: skip
            if c.significant:
                significant[kind].append(oid)
        n_obj = sum(r["object_id"] == oid for r in run.plant_rows)
        k_obj = sum(int(r["success"]) for r in run.plant_rows if r["object_id"] == oid)
        entry["plant_calibration_share"] = k_obj / n_obj if n_obj else math.nan
        objects[oid] = entry

    twin_rows = full_rows + virtual_val
    columns = list(PLANT_COLUMNS)
    write_atomic(out / "plant_validation.csv", _csv_text(plant_val, columns))
    vcols = ["object_id", "face", "conveyor", "theta_deg", "run", "seed", "status", "success",
             *DOCKING_ERROR_COLUMNS, "message"]  # fmt: skip
    write_atomic(out / "virtual_validation.csv", _csv_text(virtual_val, vcols))
    legs = ["y1", "y2"] if run.leg != "round-trip" else []  # the legs it predicts
    write_atomic(out / "fullstate.csv", _csv_text(full_rows, [*vcols, *legs]))
    return {
        "counter_measures": [m for m in COUNTER_MEASURES if m in measures],
        "f05_after": after["f05"],
        "significant_best": len(significant["best"]),
        "significant_worst": len(significant["worst"]),
        "significant_best_objects": significant["best"],
        "significant_worst_objects": significant["worst"],
        "scores_after": after,
        "objects": objects,
        "tuned_scene": tuned,
        "virtual_unstable": sum(r["status"] == "unstable" for r in twin_rows),
        "virtual_rerun": sum(str(r.get("message", "")).startswith("re-run") for r in twin_rows),
        "variant_virtual_experiments": run.virtual - virtual0,
        "_analysis": analysis,
        "_after_predictions": run_predictions(after_result),
        "_object_map": object_map,
        "_scene": scene,
    }


def _thresholds(run: _Run, main: Mapping[str, object]) -> tuple[tuple[float, float], str]:
    """The decision thresholds of the twin before and after calibration, chosen on the
    training rows as `calibrate evaluate` chooses them (its replays of them: R runs a row);
    with R = 1 every threshold in (0, 1] gives the same decisions: 0.5, no replay."""
    if run.cfg.runs == 1 or not run.train:
        return (0.5, 0.5), "0.5 (R = 1: P is 0 or 1, every threshold gives the same decisions)"
    y = [int(r["success"]) for r in run.train]
    run.stage("decision thresholds: replay of the training experiments before and after")
    p_before = run_predictions(run.replay(run.train, run.cfg.scene)).mean(axis=0)
    p_after = run_predictions(run.replay(run.train, main["_scene"], main["_object_map"]))
    tb, ta = training_threshold(p_before, y), training_threshold(p_after.mean(axis=0), y)
    return (tb, ta), f"chosen on the {len(y)} training rows (best F0.5 there)"


class Plant(Protocol):
    """What a rehearsal asks of the physical side: E^P (`EmulatedPlant.run`'s rows,
    `PLANT_COLUMNS`) and, for the mass counter-measure, a scale (`EmulatedPlant.weigh`)."""

    def run(self, requests: Sequence[PlantRequest], *, workers: int = 1,
            on_progress: Progress | None = None) -> list[dict[str, object]]: ...  # fmt: skip

    def weigh(self, object_id: str): ...


def rehearse(
    config: RehearsalConfig,
    out: Path,
    *,
    on_stage: Stage | None = None,
    on_progress: Progress | None = None,
    plant: Plant | None = None,
    measures: Sequence[str] = COUNTER_MEASURES,
    leg: str = "round-trip",
) -> dict[str, object]:
    """Run one rehearsal and write its outputs into `out` (created if needed).

    `plant` is the physical side (None: the `EmulatedPlant` of ``config.plant_seed`` and
    ``config.plant_kind``, whose seed goes to ``plant.secret``; given, e.g. a floor's
    physical units, its rows are all the rehearsal knows of it, and ``config``'s plant
    fields are unused). `measures` are the counter-measures the twin uses (a plant with no
    scale: without 'mass'). `leg` is what the full-state prediction simulates (`LEGS`:
    'operation' predicts both legs of a floor's transport operation, its y1 and y2 in
    ``fullstate.csv``); calibration and validation replay the plant's experiments, which
    go there and back ('round-trip').

    Writes ``rehearsal.json``, ``plant_calibration.csv``, ``plant_validation.csv``,
    ``virtual_validation.csv``, ``fullstate.csv`` and ``objects/<id>.proxy.json``, and the
    plant's seed in ``plant.secret`` (owner-only; ``rehearsal.json`` does not hold it); with
    ``config.ablate`` one folder ``ablate-<measure>/`` per switched-off counter-measure
    (the same files of that twin), and with ``config.operations`` ``operations.json``.

    Returns:
        The ``rehearsal.json`` document (keys `REHEARSAL_KEYS` and more).
    """
    stage = on_stage or (lambda name: None)
    progress = on_progress or (lambda done, total: None)
    cfg, t0 = config, time.perf_counter()
    bad = sorted(set(measures) - set(COUNTER_MEASURES))
    if bad:
        raise InputError(f"unknown counter-measure(s) {', '.join(bad)}")
    if plant is not None and cfg.operations:
        raise InputError("operations need the emulated plant (its operate), not a given plant")
    out.mkdir(parents=True, exist_ok=True)
    if plant is None:
        plant = EmulatedPlant(cfg.plant_seed, kind=cfg.plant_kind, mismatch_off=cfg.mismatch_off)
        write_plant_seed(out / PLANT_SEED_FILE, cfg.plant_seed)

    test_rows: list[dict[str, object]] = []
    if cfg.test_experiments:  # first, so that every K of a curve gets the same ones
        stage(f"plant: {cfg.test_experiments} held-out test experiments")
        test_design = calibration_design(cfg.objects, cfg.test_experiments, cfg.seed, "test")
        test_rows = plant.run(test_design, workers=cfg.workers, on_progress=progress)
    stage(f"plant: {cfg.calibration_experiments} calibration experiments")
    design = calibration_design(cfg.objects, cfg.calibration_experiments, cfg.seed,
                                design=cfg.design)  # fmt: skip
    plant_rows = plant.run(design, workers=cfg.workers, on_progress=progress)
    if cfg.test_experiments:
        train, test = list(plant_rows), list(test_rows)
    else:
        train, test = holdout_split(plant_rows, cfg.holdout, cfg.seed)
    y_test = [int(r["success"]) for r in test]
    run = _Run(cfg, plant, plant_rows, train, test, stage, progress, leg)

    stage("twin before calibration: replay of the held-out experiments")
    before_result = run.replay(test, cfg.scene)
    before = held_out_scores(before_result)
    before_pred = run_predictions(before_result)

    measures = frozenset(measures)
    main = _twin(run, measures, out)
    ablations: dict[str, dict[str, object]] = {}
    for m in cfg.ablate:
        stage(f"ablation: twin without the {m} counter-measure")
        var = _twin(run, measures - {m}, out / f"ablate-{m}")
        ablations[m] = {
            "dir": f"ablate-{m}",
            "f05_after_ci": f05_intervals({"after": var["_after_predictions"]}, y_test)["after"],
            **{k: var[k] for k in ("counter_measures", "f05_after", "significant_best",
                                   "significant_worst", "significant_best_objects",
                                   "significant_worst_objects", "scores_after",
                                   "virtual_unstable", "virtual_rerun")},
            "delta_f05_after": var["f05_after"] - main["f05_after"],
            "delta_significant_best": var["significant_best"] - main["significant_best"],
            "delta_significant_worst": var["significant_worst"] - main["significant_worst"],
        }  # fmt: skip

    operations = None
    if cfg.operations:
        stage(f"operations: {cfg.operations} orders with predictions and with random placement")
        operations = run_operations(
            plant, main["_analysis"], run.plant_rows, cfg.operations, seed=cfg.seed,
            workers=cfg.workers, on_progress=progress,
        )  # fmt: skip
        write_atomic(out / "operations.json", json.dumps(operations, indent=2) + "\n")

    thresholds, source = _thresholds(run, main)
    ci = f05_intervals({"before": before_pred, "after": main["_after_predictions"]}, y_test)
    held = [{**r, "p_before": float(np.mean(before_pred[:, i])),
             "p_after": float(np.mean(main["_after_predictions"][:, i]))}
            for i, r in enumerate(test)]  # fmt: skip
    write_atomic(out / "held_out_predictions.csv",
                 _csv_text(held, [*PLANT_COLUMNS, "p_before", "p_after"]))  # fmt: skip
    doc: dict[str, object] = {
        "f05_before": before["f05"],
        "f05_before_ci": ci["before"],
        "f05_after_ci": ci["after"],
        "f05_base_rate_ci": ci["base_rate"],
        "f05_delta_ci": ci["after_minus_before"],
        "thresholded": majority_scores([h["p_before"] for h in held],
                                       [h["p_after"] for h in held], y_test, seed=cfg.seed,
                                       thresholds=thresholds, threshold_source=source),
        **{k: v for k, v in main.items() if not k.startswith("_")},
        "plant_experiments": len(plant_rows)
        + len(test_rows)
        + run.plant_validation
        + (operations["plant_experiments"] if operations else 0),
        "virtual_experiments": run.virtual,
        "scores_before": before,
        "f05_base_rate": base_rate_f05(y_test),
        "held_out": len(test),
        "training": len(train),
        "ablations": ablations,
        "operations": operations,
        "config": config_record(cfg),
        **({"fullstate_leg": leg} if leg != "round-trip" else {}),
        "seconds": round(time.perf_counter() - t0, 1),
        "note": (
            "f05_* are mean per-run F0.5 of the twin's replay of held-out plant experiments "
            "(never used in calibration), *_ci their 95 % percentile-bootstrap intervals over "
            "the held-out rows (paired: f05_delta_ci is after - before on the same resamples); "
            "significant_* count objects whose best/worst state "
            "differs between twin and plant (Newcombe hybrid score interval of p_V - p_P "
            "excludes 0, alpha 0.05). The twin runs with the counter-measures "
            "'counter_measures'; 'ablations' repeats calibration, prediction and validation "
            "with one of them switched off (delta_* = without - with)."
        ),
    }
    doc.pop("variant_virtual_experiments", None)
    write_atomic(out / "plant_calibration.csv", _csv_text(plant_rows, list(PLANT_COLUMNS)))
    if test_rows:
        write_atomic(out / "plant_test.csv", _csv_text(test_rows, list(PLANT_COLUMNS)))
    write_atomic(out / "rehearsal.json", json.dumps(doc, indent=2, default=_json) + "\n")
    return doc


#: Keys of one point of the experiments-needed curve.
CURVE_KEYS = (
    "calibration_experiments", "f05_before", "f05_after", "f05_base_rate", "significant_best",
    "significant_worst", "held_out", "plant_experiments", "f05_before_ci", "f05_after_ci",
    "f05_base_rate_ci", "f05_delta_ci",
)  # fmt: skip


def curve_document(docs: Sequence[Mapping[str, object]]) -> dict[str, object]:
    """The ``rehearsal.json`` of several K: one curve point per rehearsal (`CURVE_KEYS`),
    ordered by K, and each K's folder."""
    points = []
    for doc in docs:
        k = int(doc["config"]["calibration_experiments"])  # type: ignore[index]
        points.append({"calibration_experiments": k,
                       **{key: doc.get(key) for key in CURVE_KEYS[1:]}})  # fmt: skip
    points.sort(key=lambda p: p["calibration_experiments"])
    objects = docs[0]["config"]["objects"] if docs else ()  # type: ignore[index]
    return {
        "calibration_experiments": [p["calibration_experiments"] for p in points],
        "curve": points,
        "objects": list(objects),
        "folders": {
            str(p["calibration_experiments"]): f"K{p['calibration_experiments']}" for p in points
        },
        "note": "F0.5 on held-out plant experiments and objects with a significantly different "
        "best/worst state, against the number K of plant calibration experiments.",
    }


def _json(value: object) -> object:
    if isinstance(value, np.generic):
        return value.item()
    if isinstance(value, DockingError):
        return value.as_mm_deg()
    raise TypeError(f"not JSON serialisable: {type(value).__name__}")


def _collect(rows, total: int, progress: Progress) -> list[dict[str, object]]:
    out = []
    progress(0, total)
    for row in rows:
        out.append(row)
        progress(len(out), total)
    order = {"front": 0, "back": 1, "left": 0, "both": 1, "right": 2}
    return sorted(out, key=lambda r: (str(r["object_id"]), order[str(r["face"])],
                                      order[str(r["conveyor"])], int(r["theta_deg"]),
                                      int(r["run"])))  # fmt: skip
