"""Parameter studies on top of the virtual calibration (Sec. 6.5.1, 6.5.2).

- `sweep`: vary one setting at a time (a physics option of Table A.4's analogue, or μ_k /
  d_gap as in Fig. 6.14) and score each value with R calibration runs.
- `tune_lhs`: the study's two-round Latin hypercube over a search space (by default μ_k and
  d_gap, Table A.5, Fig. 6.15): the second round samples a box shrunk around the first
  round's best.
- `tune_tpe` (module `_tpe`): a resumable optuna TPE search over the same spaces.

Every evaluation is a full `calibrate` call; the objective is the mean of a metric over
runs, F0.5 by default (the study's conservative choice), or the Brier score of the per-row
success probabilities (lower is better). A search space may hold proxy depths
(``object.<id>.<face>_depth_mm``, `transfertwin.study.calibration._space`): each trial then
replays its rows with proxies written to a work folder under a content-addressed name.
"""

from __future__ import annotations

import contextlib
import hashlib
import json
import logging
import tempfile
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from scipy.stats import qmc

from transfertwin._errors import InputError
from transfertwin.objects import PROXY_SUFFIX, write_proxy
from transfertwin.sim import SceneConfig
from transfertwin.study.calibration._replay import CalibrationResult, calibrate, parse_object_map
from transfertwin.study.calibration._space import (
    SearchSpace,
    default_space,
    parse_space,
    scene_with,
    trial_proxies,
)

__all__ = [
    "METRICS",
    "SIM_PARAMETER_SETS",
    "Trial",
    "best_trial",
    "higher_is_better",
    "replay_trial",
    "simulation_parameter_study",
    "sweep",
    "tune_lhs",
]

log = logging.getLogger(__name__)

#: Objectives: means over runs of a run metric, or the Brier score of P(success) per row.
METRICS = ("f05", "accuracy", "precision", "recall", "brier")


def higher_is_better(metric: str) -> bool:
    """False for the Brier score (a loss), True for the run metrics."""
    return metric != "brier"


@dataclass(frozen=True)
class Trial:
    """One evaluated parameter set; `penalty` is the regularisation term already weighted
    (added to a loss, subtracted from a score)."""

    label: str
    params: dict[str, object]
    result: CalibrationResult
    metric: str
    penalty: float = 0.0

    @property
    def score(self) -> float:
        """Mean of the objective metric over runs; for 'brier', the Brier score of the
        per-row success share over runs."""
        if self.metric == "brier":
            p = self.result.probabilities()
            return float(np.mean((p - np.asarray(self.result.actual)) ** 2))
        return self.result.metric(self.metric)

    @property
    def objective(self) -> float:
        """`score` with the penalty applied (what the search optimises)."""
        return self.score + (self.penalty if self.metric == "brier" else -self.penalty)

    def scores(self) -> list[float]:
        """The objective metric of every run (for box/violin plots); for 'brier', each
        run's 0/1 predictions scored as probabilities."""
        if self.metric == "brier":
            y = np.asarray(self.result.actual)
            return [float(np.mean((np.asarray(r.predicted) - y) ** 2)) for r in self.result.runs]
        return [getattr(r.confusion, self.metric) for r in self.result.runs]


def _check_metric(metric: str) -> None:
    if metric not in METRICS:
        raise InputError(f"unknown metric {metric!r}: choose one of {', '.join(METRICS)}")


def replay_trial(
    rows: Sequence[Mapping[str, object]],
    base: SceneConfig,
    params: Mapping[str, object],
    *,
    work_dir: Path | None = None,
    object_map: Mapping[str, str] | None = None,
    **calib: object,
) -> CalibrationResult:
    """`calibrate` with the scene settings and proxy depths of `params`.

    Proxies are written to `work_dir` (a temporary folder if None) as
    ``<id>-<sha256 of the proxy>.proxy.json`` and removed afterwards: the name is a function
    of the content, so a file is never rewritten with other content under the same name (the
    per-process object caches key on the path) and a second run writes the same bytes."""
    ids = sorted({str(r["object_id"]) for r in rows})
    mapping = dict(object_map) if object_map is not None else parse_object_map(None, ids)
    proxies = trial_proxies(params, mapping)
    scene = scene_with(base, params)
    if not proxies:
        return calibrate(rows, scene=scene, object_map=mapping, **calib)
    temporary = tempfile.TemporaryDirectory(prefix="tune-") if work_dir is None else None
    with temporary or contextlib.nullcontext():
        folder = Path(temporary.name if temporary is not None else work_dir)
        folder.mkdir(parents=True, exist_ok=True)
        written = []
        try:
            for oid, spec in proxies.items():
                text = json.dumps(spec.to_dict(), sort_keys=True)
                digest = hashlib.sha256(text.encode()).hexdigest()[:16]
                path = write_proxy(spec, folder / f"{oid}-{digest}{PROXY_SUFFIX}")
                written.append(path)
                mapping[oid] = str(path)
            return calibrate(rows, scene=scene, object_map=mapping, **calib)
        finally:
            for path in written:
                path.unlink(missing_ok=True)


def _evaluate(
    rows: Sequence[Mapping[str, object]], base: SceneConfig, params: Mapping[str, object],
    label: str, metric: str, **calib: object,
) -> Trial:  # fmt: skip
    result = replay_trial(rows, base, params, **calib)
    trial = Trial(label, dict(params), result, metric)
    log.info("%s %s: %s = %.4f", label, params, metric, trial.score)
    return trial


def best_trial(trials: Sequence[Trial]) -> Trial:
    """Best objective (highest, or lowest for the Brier score); ties go to the earlier
    trial."""
    if not trials:
        raise InputError("no trials to choose from")
    sign = 1.0 if higher_is_better(trials[0].metric) else -1.0
    return max(trials, key=lambda t: (sign * t.objective, -trials.index(t)))


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
    ("S10", {"physics.condim": 4}),
    ("S11", {"physics.condim": 6}),
    ("S12", {"physics.integrator": "RK4"}),
    ("S13", {"physics.max_hulls": 8}),
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


def _space(space: SearchSpace | Mapping[str, tuple[float, float]], base: SceneConfig):
    """A `SearchSpace` from a space or a {name: (low, high)} mapping (checked)."""
    if isinstance(space, SearchSpace):
        return space
    text = ",".join(f"{k}={float(lo)!r}:{float(hi)!r}" for k, (lo, hi) in space.items())
    return parse_space(text or default_space(), base)


def tune_lhs(
    rows: Sequence[Mapping[str, object]],
    space: SearchSpace | Mapping[str, tuple[float, float]],
    *,
    base: SceneConfig,
    n_per_round: int = 10,
    rounds: int = 2,
    shrink: float = 0.4,
    metric: str = "f05",
    penalty: float = 0.0,
    on_trial: Callable[[Trial], None] | None = None,
    **calib: object,
) -> list[Trial]:
    """Latin-hypercube rounds over `space`; each later round samples a box `shrink` times
    as wide, centred on the best trial so far and clipped to the original bounds (in the
    log of a log-scale dimension). The design is seeded by the calibration's `seed`;
    `penalty` weighs `SearchSpace.depth_penalty` (towards the family prior)."""
    _check_metric(metric)
    seed = int(calib.get("seed", 0))
    space = _space(space, base)
    dims = space.dims
    logs = np.array([d.log for d in dims])
    to_unit = lambda v: np.where(logs, np.log(np.maximum(v, 1e-300)), v)  # noqa: E731
    lo = to_unit(np.array([d.low for d in dims], dtype=float))
    hi = to_unit(np.array([d.high for d in dims], dtype=float))
    box_lo, box_hi = lo.copy(), hi.copy()
    trials: list[Trial] = []
    for rnd in range(rounds):
        unit = qmc.LatinHypercube(d=len(dims), seed=seed + rnd).random(n_per_round)
        points = qmc.scale(unit, box_lo, box_hi)
        for j, point in enumerate(points):
            raw = np.where(logs, np.exp(point), point)
            params = {d.name: d.value(v) for d, v in zip(dims, raw, strict=True)}
            trial = _evaluate(rows, base, params, f"I{rnd}.{j}", metric, **calib)
            weight = penalty * space.depth_penalty(params, rows)
            trial = Trial(trial.label, trial.params, trial.result, metric, weight)
            trials.append(trial)
            if on_trial is not None:
                on_trial(trial)
        best = best_trial(trials)
        centre = to_unit(np.array([float(best.params[d.name]) for d in dims]))
        half = 0.5 * shrink * (box_hi - box_lo)
        box_lo, box_hi = np.maximum(lo, centre - half), np.minimum(hi, centre + half)
    return trials
