"""Parameter studies on top of the virtual calibration (Sec. 6.5.1, 6.5.2).

- `sweep`: vary one setting at a time (a physics option of Table A.4's analogue, or μ_k /
  d_gap as in Fig. 6.14) and score each value with R calibration runs.
- `tune_lhs`: the study's two-round Latin hypercube over (μ_k, d_gap) (Table A.5,
  Fig. 6.15): the second round samples a box shrunk around the first round's best.
- `tune_tpe`: an optuna TPE search over the same box, the better alternative.

Every evaluation is a full `calibrate` call; the objective is the mean of a metric over
runs, F0.5 by default (the study's conservative choice).
"""

from __future__ import annotations

import logging
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass

import numpy as np
from scipy.stats import qmc

from transfertwin._errors import InputError
from transfertwin.sim import SceneConfig
from transfertwin.study.calibration._replay import CalibrationResult, calibrate

__all__ = [
    "METRICS",
    "SIM_PARAMETER_SETS",
    "Trial",
    "best_trial",
    "scene_with",
    "simulation_parameter_study",
    "sweep",
    "tune_lhs",
    "tune_tpe",
]

log = logging.getLogger(__name__)

METRICS = ("f05", "accuracy", "precision", "recall")
_TUNABLE = {"mu": "mu", "gap_mm": "gap_m"}


@dataclass(frozen=True)
class Trial:
    """One evaluated parameter set."""

    label: str
    params: dict[str, object]
    result: CalibrationResult
    metric: str

    @property
    def score(self) -> float:
        """Mean of the objective metric over runs."""
        return self.result.metric(self.metric)

    def scores(self) -> list[float]:
        """The objective metric of every run (for box/violin plots)."""
        return [getattr(r.confusion, self.metric) for r in self.result.runs]


def _check_metric(metric: str) -> None:
    if metric not in METRICS:
        raise InputError(f"unknown metric {metric!r}: choose one of {', '.join(METRICS)}")


def scene_with(base: SceneConfig, params: Mapping[str, object]) -> SceneConfig:
    changes: dict[str, object] = {}
    for key, value in params.items():
        if key == "gap_mm":
            changes["gap_m"] = float(value) / 1000.0
        else:
            changes[key] = value
    return base.with_overrides(**changes)


def _evaluate(
    rows: Sequence[Mapping[str, object]], base: SceneConfig, params: Mapping[str, object],
    label: str, metric: str, **calib: object,
) -> Trial:  # fmt: skip
    result = calibrate(rows, scene=scene_with(base, params), **calib)
    trial = Trial(label, dict(params), result, metric)
    log.info("%s %s: %s = %.4f", label, params, metric, trial.score)
    return trial


def best_trial(trials: Sequence[Trial]) -> Trial:
    """Highest mean score; ties go to the earlier trial."""
    if not trials:
        raise InputError("no trials to choose from")
    return max(trials, key=lambda t: (t.score, -trials.index(t)))


def sweep(
    rows: Sequence[Mapping[str, object]],
    param: str,
    values: Sequence[object],
    *,
    base: SceneConfig,
    metric: str = "f05",
    on_trial: Callable[[Trial], None] | None = None,
    **calib: object,
) -> list[Trial]:
    """One-at-a-time sweep of `param` (a scene setting such as 'mu', 'gap_mm',
    'physics.solver', 'physics.timestep_s') over `values`."""
    _check_metric(metric)
    if not values:
        raise InputError("a sweep needs at least one value")
    trials = []
    for i, value in enumerate(values):
        trial = _evaluate(rows, base, {param: value}, f"S{i}", metric, **calib)
        trials.append(trial)
        if on_trial is not None:
            on_trial(trial)
    return trials


# Our analogue of Table A.4: MuJoCo settings varied one at a time against the defaults (S0).
SIM_PARAMETER_SETS: tuple[tuple[str, dict[str, object]], ...] = (
    ("S0", {}),
    ("S1", {"physics.timestep_s": 0.001}),
    ("S2", {"physics.timestep_s": 0.004}),
    ("S3", {"physics.solver": "CG"}),
    ("S4", {"physics.solver": "PGS"}),
    ("S5", {"physics.cone": "pyramidal"}),
    ("S6", {"physics.iterations": 20}),
    ("S7", {"physics.impratio": 10.0}),
    ("S8", {"physics.noslip_iterations": 5}),
    ("S9", {"physics.multiccd": False}),
    ("S10", {"physics.condim": 3}),
    ("S11", {"physics.condim": 6}),
    ("S12", {"physics.integrator": "RK4"}),
)


def simulation_parameter_study(
    rows: Sequence[Mapping[str, object]],
    *,
    base: SceneConfig,
    sets: Sequence[tuple[str, Mapping[str, object]]] = SIM_PARAMETER_SETS,
    metric: str = "f05",
    on_trial: Callable[[Trial], None] | None = None,
    **calib: object,
) -> list[Trial]:
    """Evaluate each labelled parameter set (one setting changed from `base`) with R
    calibration runs (Sec. 6.5.1). Choose with `best_trial`."""
    _check_metric(metric)
    trials = []
    for label, params in sets:
        trial = _evaluate(rows, base, params, label, metric, **calib)
        trials.append(trial)
        if on_trial is not None:
            on_trial(trial)
    return trials


def _check_bounds(bounds: Mapping[str, tuple[float, float]]) -> None:
    for key, (lo, hi) in bounds.items():
        if key not in _TUNABLE:
            raise InputError(f"cannot tune {key!r}: tunable are {', '.join(_TUNABLE)}")
        if not lo < hi:
            raise InputError(f"bounds of {key} must satisfy low < high, got ({lo}, {hi})")


def tune_lhs(
    rows: Sequence[Mapping[str, object]],
    bounds: Mapping[str, tuple[float, float]],
    *,
    base: SceneConfig,
    n_per_round: int = 10,
    rounds: int = 2,
    shrink: float = 0.4,
    metric: str = "f05",
    on_trial: Callable[[Trial], None] | None = None,
    **calib: object,
) -> list[Trial]:
    """Latin-hypercube rounds; each later round samples a box `shrink` times as wide,
    centred on the best trial so far and clipped to the original bounds. The design is
    seeded by the calibration's `seed`."""
    _check_metric(metric)
    seed = int(calib.get("seed", 0))
    _check_bounds(bounds)
    keys = list(bounds)
    lo = np.array([bounds[k][0] for k in keys], dtype=float)
    hi = np.array([bounds[k][1] for k in keys], dtype=float)
    box_lo, box_hi = lo.copy(), hi.copy()
    trials: list[Trial] = []
    for rnd in range(rounds):
        unit = qmc.LatinHypercube(d=len(keys), seed=seed + rnd).random(n_per_round)
        points = qmc.scale(unit, box_lo, box_hi)
        for j, point in enumerate(points):
            params = {k: round(float(v), 6) for k, v in zip(keys, point, strict=True)}
            trial = _evaluate(rows, base, params, f"I{rnd}.{j}", metric, **calib)
            trials.append(trial)
            if on_trial is not None:
                on_trial(trial)
        best = best_trial(trials)
        centre = np.array([float(best.params[k]) for k in keys])
        half = 0.5 * shrink * (box_hi - box_lo)
        box_lo, box_hi = np.maximum(lo, centre - half), np.minimum(hi, centre + half)
    return trials


def tune_tpe(
    rows: Sequence[Mapping[str, object]],
    bounds: Mapping[str, tuple[float, float]],
    *,
    base: SceneConfig,
    n_trials: int = 20,
    metric: str = "f05",
    on_trial: Callable[[Trial], None] | None = None,
    **calib: object,
) -> list[Trial]:
    """optuna TPE search maximising the mean metric; the sampler is seeded by the
    calibration's `seed`."""
    import optuna

    _check_metric(metric)
    seed = int(calib.get("seed", 0))
    _check_bounds(bounds)
    optuna.logging.set_verbosity(optuna.logging.WARNING)
    trials: list[Trial] = []

    def objective(ot: optuna.Trial) -> float:
        params = {k: round(ot.suggest_float(k, lo, hi), 6) for k, (lo, hi) in bounds.items()}
        trial = _evaluate(rows, base, params, f"T{ot.number}", metric, **calib)
        trials.append(trial)
        if on_trial is not None:
            on_trial(trial)
        return trial.score

    study = optuna.create_study(direction="maximize", sampler=optuna.samplers.TPESampler(seed=seed))
    study.optimize(objective, n_trials=n_trials)
    return trials
