"""Virtual calibration (Sec. 6.5): replay real experiments in simulation and score them.

Each real experiment — its face, conveyor, θ and measured docking error — is run again as
E^V, R times with different seeds. Per run, the virtual results are compared with the real
ones as a binary classification (virtual = prediction, real = truth): confusion matrix,
precision, recall, accuracy and F0.5 (Appendix A.2), summarised as mean ± std over runs
(Table 6.4).

The real cores' meshes are not public, so real object ids map to meshes through an object
map; by default a real id maps to the built-in core with the same id.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from transfertwin._errors import InputError
from transfertwin.objects import builtin_ids
from transfertwin.ots import check_theta_deg, parse_conveyor, parse_face
from transfertwin.sim import DockingError, SceneConfig
from transfertwin.store import DOCKING_ERROR_COLUMNS
from transfertwin.study.calibration._metrics import ConfusionMatrix, summarize_runs
from transfertwin.study.experiment import (
    Executor,
    ExperimentSpec,
    experiment_seeds,
    run_rows,
)

__all__ = [
    "CalibrationResult",
    "CalibrationRun",
    "calibrate",
    "check_real_rows",
    "parse_object_map",
    "replay_specs",
]

_REQUIRED = ("object_id", "face", "conveyor", "theta_deg", "success", *DOCKING_ERROR_COLUMNS)


def parse_object_map(text: str | None, object_ids: Sequence[str]) -> dict[str, str]:
    """Map real object ids to mesh references ('o1=PATH,o18=o5'); unmapped ids map to the
    built-in core of the same id, which must exist."""
    mapping: dict[str, str] = {}
    for part in (text or "").split(","):
        if not part.strip():
            continue
        key, sep, value = part.partition("=")
        if not sep or not key.strip() or not value.strip():
            raise InputError(f"--object-map entry {part!r} is not ID=PATH")
        mapping[key.strip()] = value.strip()
    known = set(builtin_ids())
    for oid in object_ids:
        ref = mapping.setdefault(oid, oid)
        if ref not in known and not Path(ref).is_file():
            raise InputError(
                f"real object {oid!r} maps to {ref!r}, which is neither a built-in core "
                "nor a mesh file; use --object-map"
            )
    return mapping


def check_real_rows(rows: Sequence[Mapping[str, object]], source: str = "real table") -> None:
    """InputError naming `source` and the first bad row (1-based, after the header) unless
    every row is a valid real experiment: a known face and conveyor, an integer θ in
    -179..180, success 0 or 1 and a finite docking error."""
    if not rows:
        raise InputError(f"{source}: no rows")
    missing = [c for c in _REQUIRED if c not in rows[0]]
    if missing:
        raise InputError(f"{source}: missing column(s) {', '.join(missing)}")
    for i, r in enumerate(rows, start=1):
        try:
            parse_face(str(r["face"]))
            parse_conveyor(str(r["conveyor"]))
            check_theta_deg(r["theta_deg"])
            if r["success"] not in (0, 1):
                raise InputError(f"success must be 0 or 1, got {r['success']!r}")
            errors = [float(r[c]) for c in DOCKING_ERROR_COLUMNS]
            if not all(math.isfinite(e) for e in errors):
                raise InputError("docking error must be finite")
        except (InputError, TypeError, ValueError) as exc:
            raise InputError(f"{source}: row {i}: {exc}") from None


def replay_specs(
    rows: Sequence[Mapping[str, object]],
    *,
    scene: SceneConfig,
    object_map: Mapping[str, str],
    run: int,
    seed: int,
    units: str = "m",
) -> list[ExperimentSpec]:
    """One E^V spec per real row for repetition `run` (row order kept)."""
    specs = []
    for i, r in enumerate(rows):
        error = DockingError.from_mm_deg(*(float(r[c]) for c in DOCKING_ERROR_COLUMNS))
        exp_seed, _ = experiment_seeds(seed, str(r["object_id"]), i, run)
        specs.append(
            ExperimentSpec(
                object_map[str(r["object_id"])],
                str(r["face"]),
                str(r["conveyor"]),
                int(r["theta_deg"]),
                docking_error=error,
                scene=scene,
                run=run,
                seed=exp_seed,
                units=units,
            )
        )
    return specs


@dataclass(frozen=True)
class CalibrationRun:
    """One virtual calibration run: predictions per real row and their score.

    Virtual results that are not 'ok' (invalid, unstable, error) count as predicted
    failures (the conservative reading) and are tallied in `not_ok`.
    """

    run: int
    predicted: tuple[int, ...]
    confusion: ConfusionMatrix
    not_ok: int


@dataclass(frozen=True)
class CalibrationResult:
    """All runs of a virtual calibration against one real table."""

    runs: tuple[CalibrationRun, ...]
    actual: tuple[int, ...]
    object_map: dict[str, str]

    def summary(self) -> dict[str, object]:
        """Per-run metrics and their mean and std (see `summarize_runs`)."""
        return summarize_runs([r.confusion for r in self.runs])

    def probabilities(self) -> np.ndarray:
        """P(success) per real row (n,): the share of runs whose virtual transfer succeeded."""
        return np.mean([r.predicted for r in self.runs], axis=0)

    def metric(self, name: str = "f05") -> float:
        """Mean of a metric over runs (e.g. 'f05', 'accuracy', 'precision', 'recall')."""
        values = [getattr(r.confusion, name) for r in self.runs]
        return math.fsum(values) / len(values)


def calibrate(
    rows: Sequence[Mapping[str, object]],
    *,
    runs: int,
    scene: SceneConfig,
    object_map: Mapping[str, str] | None = None,
    seed: int = 0,
    workers: int = 1,
    units: str = "m",
    on_result: Callable[[], None] | None = None,
    executor: Executor | None = None,
) -> CalibrationResult:
    """Replay every real row `runs` times and score each run against the real outcomes.

    Args:
        rows: Real result rows (object_id, face, conveyor, theta_deg, success, dock_err_*).
        runs: Repetitions R (>= 1).
        scene: Virtual system configuration (the profile under test).
        object_map: Real id → mesh reference; None maps ids to built-in cores.
        seed: Master seed of the replay.
        workers: Worker processes.
        units: Length unit of mapped mesh files.
        on_result: Called after each experiment (progress).
        executor: Runs the experiments instead of `workers` local processes (e.g. a
            started `RayExecutor`); the result does not depend on it.
    """
    check_real_rows(rows)
    if runs < 1:
        raise InputError(f"--runs must be >= 1, got {runs}")
    ids = sorted({str(r["object_id"]) for r in rows})
    mapping = dict(object_map) if object_map is not None else parse_object_map(None, ids)
    actual = tuple(int(r["success"]) for r in rows)
    specs = [
        s for run in range(runs)
        for s in replay_specs(rows, scene=scene, object_map=mapping, run=run, seed=seed,
                              units=units)
    ]  # fmt: skip
    index = {(s.run, s.seed): i % len(rows) for i, s in enumerate(specs)}
    if len(index) != len(specs):
        raise RuntimeError("replay seeds collide; use another --seed")
    predicted = [[0] * len(rows) for _ in range(runs)]
    not_ok = [0] * runs
    for row in run_rows(specs, workers, executor):
        r, i = int(row["run"]), index[(int(row["run"]), int(row["seed"]))]
        if row["status"] == "ok":
            predicted[r][i] = int(row["success"])
        else:
            not_ok[r] += 1
        if on_result is not None:
            on_result()
    result_runs = tuple(
        CalibrationRun(r, tuple(p), ConfusionMatrix.from_predictions(p, actual), not_ok[r])
        for r, p in enumerate(predicted)
    )
    return CalibrationResult(result_runs, actual, mapping)
