"""Object calibration without a scan: a proxy's protrusion depth per face from real outcomes.

For one real object, every face it was tried on gets a grid of candidate proxies: the base
object (the family prior, no protrusion) and the base object with a protrusion of increasing
depth below that face's resting plane (`transfertwin.objects.Protrusion`). Each candidate
replays that face's real rows R times with the same seeds (common random numbers), which
gives P(success) per row and candidate. The chosen depth per face minimises the Brier score
plus a penalty that grows with the distance from the prior (`choose_candidates`). The
candidates' predictions are kept, so that `calibrate evaluate` can repeat the choice inside
each cross-validation training fold without simulating again.

The result is a proxy: it reproduces how often the object catches in the gap between the
docked belts, not the real object's shape.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from transfertwin._errors import InputError
from transfertwin.objects import PROXY_SUFFIX, Protrusion, ProxySpec, write_proxy
from transfertwin.sim import SceneConfig
from transfertwin.study.calibration._evaluate import choose_candidates
from transfertwin.study.calibration._replay import check_real_rows, replay_specs
from transfertwin.study.experiment import Executor, run_rows

__all__ = [
    "FaceFit",
    "ProxyFit",
    "candidates_path",
    "fit_proxy",
    "fitted_candidates",
    "load_candidates",
    "save_candidates",
]


@dataclass(frozen=True)
class FaceFit:
    """Candidates of one face: depths (k,) m, P(success) (k, n_face), the real rows'
    experiment ids (n_face,), their outcomes and the chosen candidate index."""

    face: str
    depths_m: np.ndarray
    probabilities: np.ndarray
    experiment_ids: np.ndarray
    actual: np.ndarray
    chosen: int


@dataclass(frozen=True)
class ProxyFit:
    """The calibrated proxy of one real object and the evidence behind it."""

    spec: ProxySpec
    faces: tuple[FaceFit, ...]


def _candidate(
    work_dir: Path, object_id: str, base: str, face: str, depth_m: float
) -> tuple[str, str]:
    """(object id, file) of one candidate proxy: `base` with a protrusion on `face`."""
    name = f"{object_id}~{face}{round(depth_m * 1000, 2):g}"
    spec = ProxySpec(name, base, (Protrusion(face, depth_m),))
    return name, str(write_proxy(spec, work_dir / f"{name}{PROXY_SUFFIX}"))


def fit_proxy(
    rows: Sequence[Mapping[str, object]],
    object_id: str,
    *,
    depths_m: Sequence[float],
    work_dir: Path,
    scene: SceneConfig,
    base: str | None = None,
    runs: int = 2,
    seed: int = 0,
    workers: int = 1,
    penalty: float = 0.02,
    on_progress: Callable[[int, int], None] | None = None,
    executor: Executor | None = None,
) -> ProxyFit:
    """Fit the protrusion depth of each face of `object_id` to its real rows.

    Args:
        rows: Real result rows (any objects; those of `object_id` are used). Each needs an
            `experiment_id`.
        object_id: The real object's id.
        depths_m: Candidate depths (m), ascending; 0 (the prior) is added if missing.
        work_dir: Where the candidate proxy files go.
        scene: The scene (profile) to simulate in.
        base: Base object reference (default: the built-in core of the same id).
        runs: Repetitions R per row and candidate (placement noise from the seed).
        seed: Master seed.
        workers: Worker processes.
        penalty: Brier-score penalty at the deepest candidate (linear in the grid index).
        on_progress: Called with (done, total) experiments.
        executor: Runs the experiments instead of `workers` local processes (e.g. a
            started `RayExecutor`; candidate files in `work_dir` must then be readable
            where the experiments run).
    """
    mine = [r for r in rows if str(r["object_id"]) == object_id]
    if not mine:
        raise InputError(f"no real rows of object {object_id!r}")
    check_real_rows(mine, f"rows of {object_id}")
    if "experiment_id" not in mine[0]:
        raise InputError("the real table needs an experiment_id column")
    if runs < 1:
        raise InputError(f"runs must be at least 1, got {runs}")
    depths = np.unique(np.r_[0.0, np.asarray(depths_m, dtype=float)])
    base = base or object_id
    work_dir.mkdir(parents=True, exist_ok=True)
    faces = sorted({str(r["face"]) for r in mine})
    specs, where = [], {}
    for face in faces:
        face_rows = [r for r in mine if r["face"] == face]
        for k, depth in enumerate(depths):
            name, ref = _candidate(work_dir, object_id, base, face, float(depth))
            for run in range(runs):
                batch = replay_specs(face_rows, scene=scene, object_map={object_id: ref},
                                     run=run, seed=seed)  # fmt: skip
                for i, s in enumerate(batch):
                    where[(name, s.run, s.seed)] = (face, k, i)
                specs += batch
    wins = {f: np.zeros((len(depths), sum(r["face"] == f for r in mine))) for f in faces}
    for done, row in enumerate(run_rows(specs, workers, executor), start=1):
        face, k, i = where[(str(row["object_id"]), int(row["run"]), int(row["seed"]))]
        wins[face][k, i] += 1 if row["status"] == "ok" and row["success"] == 1 else 0
        if on_progress is not None:
            on_progress(done, len(specs))
    fits, protrusions = [], []
    for face in faces:
        face_rows = [r for r in mine if r["face"] == face]
        p = wins[face] / runs
        y = np.array([int(r["success"]) for r in face_rows])
        groups = np.array([face] * len(face_rows))
        chosen = choose_candidates({face: p}, groups, y, np.arange(len(y)), penalty)[face]
        ids = np.array([int(r["experiment_id"]) for r in face_rows])
        fits.append(FaceFit(face, depths, p, ids, y, chosen))
        protrusions.append(Protrusion(face, float(depths[chosen])))
    spec = ProxySpec(object_id, base, tuple(protrusions))
    return ProxyFit(spec, tuple(fits))


def candidates_path(folder: Path, object_id: str) -> Path:
    """Where `calibrate object` keeps the candidates of `object_id` in `folder`."""
    return folder / f"{object_id}.candidates.npz"


def save_candidates(fit: ProxyFit, path: Path) -> Path:
    """The candidates' predictions as .npz (read back by `load_candidates`)."""
    arrays = {}
    for f in fit.faces:
        arrays[f"{f.face}_depths_m"] = f.depths_m
        arrays[f"{f.face}_p"] = f.probabilities
        arrays[f"{f.face}_ids"] = f.experiment_ids
        arrays[f"{f.face}_chosen"] = np.array(f.chosen)
    np.savez(path, object_id=np.array(fit.spec.object_id), **arrays)
    return path


def load_candidates(
    path: Path, experiment_ids: np.ndarray
) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    """Group 'object:face' → (candidate predictions (k, n) aligned with `experiment_ids`,
    NaN on other rows; row mask (n,)). InputError if a fitted row is missing."""
    pos = {int(e): j for j, e in enumerate(experiment_ids)}
    with np.load(path) as data:
        obj = str(data["object_id"])
        out = {}
        for face in ("front", "back"):
            if f"{face}_p" not in data:
                continue
            p, ids = data[f"{face}_p"], data[f"{face}_ids"]
            if any(int(e) not in pos for e in ids):
                raise InputError(f"{path}: fitted rows missing from the real table")
            full = np.full((p.shape[0], len(experiment_ids)), np.nan)
            cols = [pos[int(e)] for e in ids]
            full[:, cols] = p
            mask = np.zeros(len(experiment_ids), dtype=bool)
            mask[cols] = True
            out[f"{obj}:{face}"] = (full, mask)
    return out


def fitted_candidates(
    folder: Path, rows: Sequence[Mapping[str, object]]
) -> tuple[dict[str, np.ndarray], np.ndarray]:
    """Candidate predictions per 'object:face' group for `rows` from the `calibrate object`
    outputs in `folder`, and each row's group (n,). InputError if anything is missing."""
    ids = np.array([int(r["experiment_id"]) for r in rows])
    candidates = {}
    for obj in sorted({str(r["object_id"]) for r in rows}):
        path = candidates_path(folder, obj)
        if not path.is_file():
            raise InputError(f"{path}: missing; run 'transfertwin calibrate object --object {obj}'")
        candidates |= {group: pred for group, (pred, _) in load_candidates(path, ids).items()}
    groups = np.array([f"{r['object_id']}:{r['face']}" for r in rows])
    missing = sorted(set(groups) - set(candidates))
    if missing:
        raise InputError(f"{folder}: no fitted candidates for {', '.join(missing)}")
    return candidates, groups
