"""A joint, resumable optuna TPE search over scene settings and proxy depths.

The study lives in an optuna RDB storage (e.g. ``sqlite:///tune/tune.sqlite``) under a name
derived from everything that defines the objective (`study_settings`): the real rows, the
search space, runs, seed, metric, penalty, the base scene and the object map (file contents
by hash). Running the same search again continues that study: it adds only the trials
missing up to `n_trials` complete ones. Any other setting gives another name, so a changed
command starts a new study beside the old one in the same storage; an explicit
`study_name` whose stored settings differ is refused.

Only complete trials count. A trial that raised (Ctrl-C included) is marked failed by
optuna; one left 'running' by a killed process is marked failed when the study is opened
again (one process per study at a time). Trial k (the k-th complete trial, from 0) is
sampled by a TPE sampler seeded with (seed, k): the sequence of trials depends on the seed
and the completed history only, so an interrupted and resumed search proposes the same
trials as an uninterrupted one. The first `STARTUP_TRIALS` trials are random (optuna's
default), TPE models the rest (multivariate).
"""

from __future__ import annotations

import hashlib
import json
import math
import warnings
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from transfertwin._errors import InputError
from transfertwin.sim import SceneConfig
from transfertwin.study.calibration._replay import CalibrationResult
from transfertwin.study.calibration._space import SearchSpace
from transfertwin.study.calibration._tuning import (
    Trial,
    _check_metric,
    higher_is_better,
    replay_trial,
)
from transfertwin.study.experiment import scene_to_dict

__all__ = [
    "STARTUP_TRIALS",
    "TuneStudy",
    "TunedTrial",
    "open_storage",
    "study_name_for",
    "study_settings",
    "tune_tpe",
    "tuned_trial",
]

#: Random trials before TPE models the history (optuna's default).
STARTUP_TRIALS = 10
_VERSION = 1


@dataclass(frozen=True)
class TunedTrial:
    """One complete trial: the values used, its objective and metrics.

    `metrics` holds f05, f05_std, precision, recall, accuracy (means over runs), brier (of
    the per-row success share) and not_ok (virtual runs that were not 'ok');
    `scores` the objective metric per run; `penalty` the weighted regularisation term."""

    number: int
    params: dict[str, object]
    objective: float
    metrics: dict[str, float]
    penalty: float
    scores: tuple[float, ...]


def _metrics(result: CalibrationResult) -> dict[str, float]:
    summary = result.summary()["metrics"]
    out = {k: float(summary[k]["mean"]) for k in ("f05", "precision", "recall", "accuracy")}
    std = summary["f05"]["std"]
    out["f05_std"] = float(std) if math.isfinite(std) else float("nan")
    p = result.probabilities()
    out["brier"] = float(np.mean((p - np.asarray(result.actual)) ** 2))
    out["not_ok"] = float(sum(r.not_ok for r in result.runs))
    return out


def tuned_trial(number: int, trial: Trial) -> TunedTrial:
    """A `TunedTrial` from an evaluated `Trial` (e.g. of `tune_lhs`)."""
    return TunedTrial(number, dict(trial.params), trial.objective, _metrics(trial.result),
                      trial.penalty, tuple(trial.scores()))  # fmt: skip


@dataclass(frozen=True)
class TuneStudy:
    """The complete trials of a tuning study, by number, and how this call changed it."""

    name: str
    metric: str
    trials: tuple[TunedTrial, ...]
    added: int
    stale: int

    def best(self) -> TunedTrial:
        """Best objective (highest; lowest for 'brier'); ties go to the earlier trial."""
        if not self.trials:
            raise InputError("no complete trials to choose from")
        sign = 1.0 if higher_is_better(self.metric) else -1.0
        return max(self.trials, key=lambda t: (sign * t.objective, -t.number))


def _file_digest(path: str) -> str:
    return hashlib.sha256(Path(path).read_bytes()).hexdigest()


def study_settings(
    rows: Sequence[Mapping[str, object]],
    space: SearchSpace,
    *,
    base: SceneConfig,
    metric: str,
    runs: int,
    seed: int,
    penalty: float,
    object_map: Mapping[str, str],
    units: str = "m",
) -> dict[str, object]:
    """Everything that defines the objective, as JSON-able data (the study's identity)."""
    from transfertwin.store import DOCKING_ERROR_COLUMNS

    canon = [
        [str(r["object_id"]), str(r["face"]), str(r["conveyor"]), int(r["theta_deg"]),
         int(r["success"]), *(repr(float(r[c])) for c in DOCKING_ERROR_COLUMNS)]
        for r in rows
    ]  # fmt: skip
    rows_hash = hashlib.sha256(json.dumps(canon).encode()).hexdigest()
    refs = {oid: (ref if not Path(ref).is_file() else f"sha256:{_file_digest(ref)}")
            for oid, ref in sorted(object_map.items())}  # fmt: skip
    return {
        "version": _VERSION, "rows_sha256": rows_hash, "n_rows": len(rows),
        "space": space.text(), "metric": metric, "runs": runs, "seed": seed,
        "penalty": penalty, "object_map": refs, "units": units,
        "startup_trials": STARTUP_TRIALS,
        "scene": json.loads(json.dumps(scene_to_dict(base), default=str)),
    }  # fmt: skip


def study_name_for(settings: Mapping[str, object]) -> str:
    """``tune-`` and the first 16 hex digits of the settings' SHA-256."""
    text = json.dumps(settings, sort_keys=True)
    return "tune-" + hashlib.sha256(text.encode()).hexdigest()[:16]


def _sampler(seed: int, k: int):
    import optuna

    state = int(np.random.SeedSequence([seed, k]).generate_state(1)[0])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", optuna.exceptions.ExperimentalWarning)
        return optuna.samplers.TPESampler(
            seed=state, multivariate=True, n_startup_trials=STARTUP_TRIALS
        )


def _suggest(ot, space: SearchSpace) -> dict[str, object]:
    params: dict[str, object] = {}
    for d in space.dims:
        if d.integer:
            params[d.name] = ot.suggest_int(d.name, int(d.low), int(d.high), log=d.log)
        else:
            params[d.name] = d.value(ot.suggest_float(d.name, d.low, d.high, log=d.log))
    return params


def open_storage(url: str):
    """optuna's RDB storage at `url` (created if missing); InputError if it cannot be
    opened."""
    import optuna
    from sqlalchemy.exc import SQLAlchemyError

    optuna.logging.set_verbosity(optuna.logging.ERROR)
    try:
        return optuna.storages.RDBStorage(url)
    except (ValueError, ImportError, SQLAlchemyError) as exc:
        reason = str(exc).splitlines()[0]
        raise InputError(f"--storage {url!r}: cannot open ({reason})") from None


def _open(storage: str | None, name: str, settings: Mapping[str, object], metric: str):
    """(optuna study, number of stale trials marked failed)."""
    import optuna
    from optuna.trial import TrialState

    optuna.logging.set_verbosity(optuna.logging.ERROR)
    store = optuna.storages.InMemoryStorage() if storage is None else open_storage(storage)
    direction = "maximize" if higher_is_better(metric) else "minimize"
    study = optuna.create_study(storage=store, study_name=name, direction=direction,
                                load_if_exists=True)  # fmt: skip
    stored = study.user_attrs.get("settings")
    if stored is None:
        study.set_user_attr("settings", json.loads(json.dumps(settings)))
    elif stored != json.loads(json.dumps(settings)):
        changed = sorted(k for k in set(stored) | set(settings) if stored.get(k) != settings.get(k))
        raise InputError(
            f"study {name!r} in {storage} was run with other settings ({', '.join(changed)}); "
            "leave out --study-name to start a study for these settings"
        )
    stale = 0
    study_id = store.get_study_id_from_name(name)
    for t in study.get_trials(deepcopy=False, states=(TrialState.RUNNING,)):
        trial_id = store.get_trial_id_from_study_id_trial_number(study_id, t.number)
        store.set_trial_state_values(trial_id, TrialState.FAIL)
        stale += 1
    return study, stale


def _complete(study) -> list[TunedTrial]:
    from optuna.trial import TrialState

    out = []
    for t in study.get_trials(deepcopy=False, states=(TrialState.COMPLETE,)):
        a = t.user_attrs
        out.append(TunedTrial(t.number, dict(a["params"]), float(t.value),
                              {k: float("nan") if v is None else float(v)
                               for k, v in a["metrics"].items()},
                              float(a["penalty"]), tuple(a["scores"])))  # fmt: skip
    return sorted(out, key=lambda t: t.number)


def _jsonable(metrics: Mapping[str, float]) -> dict[str, float | None]:
    return {k: (v if math.isfinite(v) else None) for k, v in metrics.items()}


def tune_tpe(
    rows: Sequence[Mapping[str, object]],
    space: SearchSpace,
    *,
    base: SceneConfig,
    n_trials: int = 20,
    metric: str = "f05",
    penalty: float = 0.0,
    storage: str | None = None,
    study_name: str | None = None,
    work_dir: Path | None = None,
    on_trial: Callable[[TunedTrial], None] | None = None,
    on_progress: Callable[[int, int], None] | None = None,
    **calib: object,
) -> TuneStudy:
    """Run TPE trials until the study holds `n_trials` complete ones (see the module doc).

    Args:
        rows: Real result rows.
        space: The joint search space (`parse_space`).
        base: The scene the space's settings are applied to.
        n_trials: Complete trials wanted in the study (earlier runs' trials count).
        metric: Objective: 'f05' (default, maximised) or another run metric, or 'brier'
            (minimised; the Brier score of the per-row success share over runs).
        penalty: Weight of `SearchSpace.depth_penalty` (towards the family prior),
            subtracted from a score, added to the Brier score.
        storage: optuna RDB URL, e.g. ``sqlite:///tune.sqlite``; None keeps the study in
            memory (not resumable).
        study_name: None derives it from the settings (`study_name_for`).
        work_dir: Folder for the trials' proxy files (see `replay_trial`).
        on_trial: Called with each new complete trial.
        on_progress: Called with (done, total) experiments of this call.
        **calib: `calibrate` arguments: runs, seed, object_map, workers, units, executor.
    """
    import optuna

    _check_metric(metric)
    if n_trials < 1:
        raise InputError(f"--trials must be >= 1, got {n_trials}")
    if not (math.isfinite(penalty) and penalty >= 0):
        raise InputError(f"--penalty must be >= 0, got {penalty}")
    runs, seed = int(calib["runs"]), int(calib.get("seed", 0))
    object_map = calib.get("object_map")
    if object_map is None:
        from transfertwin.study.calibration._replay import parse_object_map

        object_map = parse_object_map(None, sorted({str(r["object_id"]) for r in rows}))
        calib["object_map"] = object_map
    settings = study_settings(rows, space, base=base, metric=metric, runs=runs, seed=seed,
                              penalty=penalty, object_map=object_map,
                              units=str(calib.get("units", "m")))  # fmt: skip
    name = study_name or study_name_for(settings)
    study, stale = _open(storage, name, settings, metric)
    done_before = len(_complete(study))
    missing = max(0, n_trials - done_before)
    total = missing * len(rows) * runs
    progress = {"done": 0}

    def tick() -> None:
        progress["done"] += 1
        if on_progress is not None:
            on_progress(progress["done"], total)

    def objective(ot: optuna.Trial) -> float:
        params = _suggest(ot, space)
        trial = Trial(f"T{ot.number}", params,
                      replay_trial(rows, base, params, work_dir=work_dir, on_result=tick,
                                   **calib),
                      metric, penalty * space.depth_penalty(params, rows))  # fmt: skip
        metrics = _metrics(trial.result)
        ot.set_user_attr("params", params)
        ot.set_user_attr("metrics", _jsonable(metrics))
        ot.set_user_attr("penalty", trial.penalty)
        ot.set_user_attr("scores", trial.scores())
        if on_trial is not None:
            on_trial(tuned_trial(ot.number, trial))
        return trial.objective

    if on_progress is not None:
        on_progress(0, total)
    for k in range(done_before, n_trials):
        study.sampler = _sampler(seed, k)
        study.optimize(objective, n_trials=1)
    trials = _complete(study)
    return TuneStudy(name, metric, tuple(trials), len(trials) - done_before, stale)
