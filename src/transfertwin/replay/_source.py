"""Where a replay comes from: a study store's row, a calibration's row, or a `transfer`'s
arguments.

A study row's experiment is rebuilt from the store's plan (`StudyPlan.specs`, which derives
every seed and docking error from the master seed, the object, the state and the run), so
the replay is the experiment the study ran; `compare_with_row` says whether its result has
the stored row's bits (y1, y2, success, t_end and the pre-transfer state).

A `calibrate run` folder's row is rebuilt as `calibrate` replayed it (`replay_specs`: the
real row's state and measured docking error, the seed from the master seed, the real object
id, the row index and the run) from what the folder records: the real table, the profile
(a built-in one), the object map and the number of real rows. The master seed is not
recorded there; the default 0 of `calibrate run --seed` is assumed, and the replay says
whether its outcome agrees with the run's prediction in predictions.csv.
"""

from __future__ import annotations

import dataclasses
import json
import math
from collections.abc import Mapping
from pathlib import Path

from transfertwin._errors import InputError
from transfertwin.objects import is_builtin_id, load_object
from transfertwin.ots import check_theta_deg, parse_conveyor, parse_face
from transfertwin.sim import DockingError, SceneConfig
from transfertwin.store import SQLITE_SUFFIXES, SQLiteResultStore, read_results
from transfertwin.study.experiment import (
    ExperimentResult,
    ExperimentSpec,
    StudyPlan,
    load_profile,
)

__all__ = [
    "COMPARED_COLUMNS",
    "CalibrationRow",
    "StudyRow",
    "calibration_source",
    "calibration_spec",
    "compare_with_row",
    "study_spec",
    "transfer_spec",
]

#: The result columns a replay must reproduce bit for bit.
COMPARED_COLUMNS = ("status", "y1", "y2", "success", "t_end_s", "t_end_1_s", "t_end_2_s",
                    "state_pre", "state_end_1", "state_end_2")  # fmt: skip


@dataclasses.dataclass(frozen=True)
class StudyRow:
    """One experiment of a study: its spec as the plan makes it, its stored row (None
    when the study has not run it yet), the store's file name and the plan's runs per state."""

    spec: ExperimentSpec
    row: dict[str, object] | None
    store: str
    runs: int = 1


class _AllBut:
    """A `skip` container holding every key but one (`StudyPlan.specs` then builds one spec)."""

    def __init__(self, key: tuple) -> None:
        self._key = key

    def __contains__(self, key: object) -> bool:
        return key != self._key


def _object_ref(plan: StudyPlan, object_id: str) -> str:
    """The plan's object reference whose id is `object_id`."""
    for ref in plan.objects:
        if ref == object_id and is_builtin_id(ref):
            return ref
    for ref in plan.objects:
        if not is_builtin_id(ref) and load_object(ref, units=plan.units).object_id == object_id:
            return ref
    raise InputError(f"object {object_id!r} is not in the study; its objects: "
                     f"{', '.join(plan.objects)}")  # fmt: skip


def _key(row: Mapping[str, object]) -> tuple:
    return tuple(row[k] for k in ("object_id", "face", "conveyor", "theta_deg", "run"))


def study_spec(
    db: str | Path, object_id: str, face: str, conveyor: str, theta_deg: int, run: int
) -> StudyRow:
    """The experiment (object, state, run) of the study in store `db`."""
    path = Path(db)
    if path.suffix.lower() not in SQLITE_SUFFIXES:
        raise InputError(f"--db {db}: a study store ({', '.join(SQLITE_SUFFIXES)})")
    if not path.is_file():
        raise InputError(f"--db {db}: no such file")
    face, conveyor = parse_face(face), parse_conveyor(conveyor)
    theta_deg = check_theta_deg(theta_deg)
    try:
        store = SQLiteResultStore(path, create=False)
    except InputError:
        raise
    except Exception as exc:
        raise InputError(f"--db {db}: not a result store ({exc})") from None
    with store:
        stored = store.plan()
        if stored is None:
            raise InputError(f"--db {db}: the store has no study plan")
        plan = StudyPlan.from_json(stored.plan_json)
        ref = _object_ref(plan, object_id)
        if not any((s.face, s.conveyor, s.theta_deg) == (face, conveyor, theta_deg)
                   for s in plan.states()):  # fmt: skip
            raise InputError(f"state {face}/{conveyor}/{theta_deg}° is not in the study "
                             f"(θ step {plan.theta_step})")  # fmt: skip
        if isinstance(run, bool) or not 0 <= run < plan.runs:
            raise InputError(f"--run must be in 0..{plan.runs - 1}, got {run}")
        key = (object_id, face, conveyor, theta_deg, run)
        specs = list(plan.specs({ref: object_id}, skip=_AllBut(key)))
        row = next((r for r in store.rows() if _key(r) == key), None)
    if len(specs) != 1:
        raise InputError(f"the study plans no experiment {key}")
    return StudyRow(specs[0][1], row, path.name, plan.runs)


def _same(a: object, b: object) -> bool:
    if isinstance(a, float) and isinstance(b, float) and math.isnan(a) and math.isnan(b):
        return True
    if a is None and isinstance(b, float) and math.isnan(b):
        return True
    if b is None and isinstance(a, float) and math.isnan(a):
        return True
    if isinstance(a, str) and isinstance(b, str) and a.startswith("["):
        return json.loads(a) == json.loads(b)
    return a == b or (a in ("", None) and b in ("", None))


def compare_with_row(result: ExperimentResult, row: Mapping[str, object]) -> dict[str, object]:
    """Whether `result` reproduces a stored row: {"same": bool, "differences": [...]}."""
    mine = result.row()
    diffs = [f"{k}: stored {row.get(k)!r}, replay {mine[k]!r}"
             for k in COMPARED_COLUMNS if k in row and not _same(row.get(k), mine[k])]  # fmt: skip
    return {"same": not diffs, "differences": diffs}


def transfer_spec(
    object_ref: str,
    face: str,
    conveyor: str,
    theta_deg: int,
    *,
    seed: int = 0,
    dock_error: str = "0,0,0",
    units: str = "m",
    profile: str | None = None,
    gap_mm: float | None = None,
    mu: float | None = None,
) -> ExperimentSpec:
    """The experiment `transfertwin transfer` runs for these arguments (same defaults)."""
    scene = load_profile(profile)[1] if profile else SceneConfig()
    if mu is not None:
        scene = scene.with_overrides(mu=mu)
    if gap_mm is not None:
        scene = scene.with_overrides(gap_m=gap_mm / 1000.0)
    return ExperimentSpec(
        object_ref=object_ref, face=face, conveyor=conveyor, theta_deg=theta_deg,
        docking_error=DockingError.from_text(dock_error), scene=scene, seed=seed, units=units,
    )  # fmt: skip


#: The `--real` default of `calibrate`: the real table shipped with the package.
BUILTIN_REAL = "builtin:calibration_experiments.csv"


@dataclasses.dataclass(frozen=True)
class CalibrationRow:
    """One real row of a calibration, replayed: its spec, the real outcome and the run's
    prediction (1 success; 0 failure or not 'ok'), and how the spec was rebuilt."""

    spec: ExperimentSpec
    real_success: int
    predicted: int | None
    runs: int
    note: str


def _json_object(path: Path) -> dict[str, object]:
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise InputError(f"{path.parent.name}/{path.name}: unreadable ({exc})") from None
    if not isinstance(data, dict):
        raise InputError(f"{path.parent.name}/{path.name}: not a JSON object")
    return data


def calibration_spec(folder: str | Path, row: int, run: int, seed: int = 0) -> CalibrationRow:
    """The experiment `calibrate run` (output in `folder`) ran for real row `row`, run `run`."""
    import csv

    from transfertwin.data import calibration_csv_path
    from transfertwin.study.calibration import replay_specs

    folder = Path(folder)
    metrics_path = folder / "metrics.json"
    if not metrics_path.is_file():
        raise InputError(f"{folder.name}: no metrics.json ('calibrate run' writes it); rows of "
                         "'calibrate evaluate' are not replayed")  # fmt: skip
    metrics = _json_object(metrics_path)
    try:
        n_real, runs = int(metrics["n_real"]), len(metrics["runs"])
        object_map = {str(k): str(v) for k, v in dict(metrics["object_map"]).items()}
        real, profile = str(metrics["real"]), str(metrics.get("profile") or "default")
    except (KeyError, TypeError, ValueError) as exc:
        raise InputError(f"{folder.name}/metrics.json: not written by 'calibrate run' "
                         f"({type(exc).__name__}: {exc})") from None  # fmt: skip
    if isinstance(row, bool) or not 0 <= row < n_real:
        raise InputError(f"row must be in 0..{n_real - 1}, got {row}")
    if isinstance(run, bool) or not 0 <= run < runs:
        raise InputError(f"run must be in 0..{runs - 1}, got {run}")
    path = calibration_csv_path() if real == BUILTIN_REAL else Path(real)
    if not path.is_file():
        raise InputError(f"{folder.name}: its real table {real} is not found")
    rows = list(read_results(path))[:n_real]
    scene = SceneConfig() if profile == "default" else load_profile(profile)[1]
    spec = replay_specs(rows, scene=scene, object_map=object_map, run=run, seed=seed)[row]
    predicted = None
    preds = folder / "predictions.csv"
    if preds.is_file():
        with preds.open(newline="", encoding="utf-8") as fh:
            for rec in csv.DictReader(fh):
                if rec.get("row") == str(row) and rec.get(f"pred_run{run}") in ("0", "1"):
                    predicted = int(rec[f"pred_run{run}"])
    note = (f"real row {row} of {real}, run {run}, profile {profile}, master seed {seed} "
            "(calibrate run's default; the folder does not record it)")
    return CalibrationRow(spec, int(rows[row]["success"]), predicted, runs, note)


def calibration_source(
    name: str, row: int, found: CalibrationRow, result: ExperimentResult
) -> dict[str, object]:
    """The replay document's ``source`` for a calibration row: the real outcome, the run's
    prediction and whether this replay's outcome agrees with it."""
    outcome = int(result.status == "ok" and result.success == 1)
    agrees = None if found.predicted is None else outcome == found.predicted
    return {"kind": "calibration", "calibration": name, "row": row, "run": found.spec.run,
            "runs": found.runs, "real_success": found.real_success,
            "predicted": found.predicted, "replayed": outcome, "agrees": agrees,
            "note": found.note}  # fmt: skip
