"""Object calibration without a scan: a proxy's shape and mass distribution from real outcomes.

For one real object the search space is the procedural core family's two free parameters:
a protrusion depth below each face's resting plane (`transfertwin.objects.Protrusion`, its
shape) and a centre-of-mass shift along the object's x axis shared by both faces
(`ProxySpec.com_shift_m`, two densities split across x: its mass distribution). The family
prior is the plain body of uniform density (depth 0, shift 0). Every face it was tried on gets
the grid of candidates shift × depth; each candidate replays that face's real rows R times
with the same seeds (common random numbers), which gives P(success) per row and candidate.
The chosen shift and depths minimise the Brier score plus penalties that grow with the
distance from the prior (`choose_joint`: jointly, as the shift couples the faces).

Opt-in, a face's prior is a feature the twin already holds (`prior`: e.g. a built-in
core's shipped resting features, `transfertwin.objects.builtin_features`) instead of the
plain body: that face's candidates are the prior's depth first, then the other depths by
their distance from it, so the penalty grows with the distance from what the twin knew; a
face with fewer than `min_rows` real rows keeps its prior, unsearched (few tries do not
overturn it), and so does a face without rows. Without a prior every face starts plain,
as before.

Opt-in, the protrusion's position along the object's x axis (`Protrusion.x_frac`, a
fraction of its length; the prior 0.5 is the centre) is searched with the depths: each
nonzero depth is tried at every position of the grid (depth 0 has no feature and so no
position), and a penalty growing with |x - 0.5| pulls towards the centre. With the
default grid (0.5 only) the candidates, their names and the choice are those of a
depth-only fit. The
candidates' predictions are kept, so that `calibrate evaluate` can repeat the choice inside
each cross-validation training fold without simulating again.

The result is a proxy: it reproduces how often the object catches in the gap between the
docked belts, not the real object's shape or mass distribution.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from transfertwin._errors import InputError
from transfertwin.objects import (
    PROXY_SUFFIX,
    Protrusion,
    ProxySpec,
    is_builtin_id,
    load_builtin,
    load_object,
    mass_split,
    write_proxy,
)
from transfertwin.sim import SceneConfig
from transfertwin.study.calibration._evaluate import JointCandidates, choose_joint
from transfertwin.study.calibration._replay import check_real_rows, replay_specs
from transfertwin.study.experiment import Executor, run_rows

__all__ = [
    "FaceFit",
    "ProxyFit",
    "candidates_path",
    "check_positions",
    "check_shifts",
    "fit_proxy",
    "fitted_candidates",
    "load_candidates",
    "save_candidates",
]


@dataclass(frozen=True)
class FaceFit:
    """Candidates of one face: depths (K,) m, P(success) (S, K, n_face) per shift and
    candidate, the real rows' experiment ids (n_face,), their outcomes and the chosen
    candidate index (at the chosen shift); with searched positions also each candidate's
    position along x (K,) (None: all centred, one candidate per depth)."""

    face: str
    depths_m: np.ndarray
    probabilities: np.ndarray
    experiment_ids: np.ndarray
    actual: np.ndarray
    chosen: int
    positions: np.ndarray | None = None

    def label(self, k: int) -> str:
        """Candidate `k` in words: '8 mm' or '8 mm @0.3' (position along x)."""
        text = f"{self.depths_m[k] * 1000:g} mm"
        if self.positions is not None and self.depths_m[k] > 0:
            text += f" @{self.positions[k]:g}"
        return text


@dataclass(frozen=True)
class ProxyFit:
    """The calibrated proxy of one real object and the evidence behind it.

    Attributes:
        shifts_m: Candidate centre-of-mass shifts (S,), 0 first.
        shift_chosen: Index of the chosen shift.
        front_fraction: Share of the mass in the object's front (+x, pinion) half at the
            chosen shift; uniform_front_fraction: the same at uniform density.
    """

    spec: ProxySpec
    faces: tuple[FaceFit, ...]
    shifts_m: np.ndarray
    shift_chosen: int
    front_fraction: float
    uniform_front_fraction: float


def _candidate(
    work_dir: Path,
    object_id: str,
    base: str,
    face: str,
    depth_m: float,
    shift_m: float,
    x_frac: float = 0.5,
    shape: Protrusion | None = None,
) -> tuple[str, str]:
    """(object id, file) of one candidate proxy: `base` with a protrusion on `face` (at
    `x_frac` along x; with `shape`, that feature's footprint at `depth_m`) and its centre of
    mass shifted by `shift_m`."""
    name = f"{object_id}~{face}{round(depth_m * 1000, 2):g}"
    if x_frac != 0.5:
        name += f"~x{round(x_frac, 4):g}"
    if shift_m != 0:
        name += f"~com{round(shift_m * 1000, 2):+g}"
    prot = (Protrusion(face, depth_m, x_frac=x_frac) if shape is None
            else dataclasses.replace(shape, depth_m=depth_m))  # fmt: skip
    spec = ProxySpec(name, base, (prot,), com_shift_m=shift_m)
    return name, str(write_proxy(spec, work_dir / f"{name}{PROXY_SUFFIX}"))


def _base_model(base: str):
    """The base body of a proxy built on `base` (the plain body for a built-in id)."""
    return load_builtin(base, features=False) if is_builtin_id(base) else load_object(base)


def check_shifts(base: str, shifts_m: Sequence[float]) -> None:
    """InputError unless the body of `base` can carry every centre-of-mass shift (two
    positive densities, `transfertwin.objects.axial_mass_split`)."""
    body = _base_model(base)
    for shift in sorted({float(v) for v in shifts_m} - {0.0}):
        mass_split(body, ProxySpec(base, base, (), com_shift_m=shift))


def _shift_grid(shifts_m: Sequence[float]) -> np.ndarray:
    """Distinct shifts, the prior 0 first, then by distance from it (negative first)."""
    values = {0.0, *(float(v) for v in shifts_m)}
    return np.array(sorted(values, key=lambda v: (abs(v), v)))


def check_positions(positions: Sequence[float]) -> None:
    """InputError unless every protrusion position lies in 0..1 (a fraction of the length)."""
    for v in positions:
        if not (isinstance(v, (int, float)) and 0.0 <= float(v) <= 1.0):
            raise InputError(f"protrusion positions must lie in 0..1, got {v!r}")


def _position_grid(positions: Sequence[float]) -> np.ndarray:
    """Distinct positions, the prior 0.5 first, then by distance from it (rear first)."""
    values = {0.5, *(float(v) for v in positions)}
    return np.array(sorted(values, key=lambda v: (abs(v - 0.5), v)))


def _face_grid(depths: np.ndarray, positions: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """A face's candidates (K,) as depths and positions: depth 0 (no feature) once, then each
    nonzero depth, ascending, at every position (the centre first)."""
    pairs = [(0.0, 0.5)] + [(float(d), float(x)) for d in depths[1:] for x in positions]
    return np.array([d for d, _ in pairs]), np.array([x for _, x in pairs])


def _prior_grid(depths: np.ndarray, prior: Protrusion) -> tuple[np.ndarray, np.ndarray]:
    """A face's candidates (K,) around its `prior` feature: the prior's depth first, then the
    other depths by their distance from it (shallower first on a tie); all at the prior's
    position along x."""
    d0 = float(prior.depth_m)
    others = sorted({float(d) for d in depths} - {d0}, key=lambda d: (abs(d - d0), d))
    grid = np.array([d0, *others])
    return grid, np.full(len(grid), float(prior.x_frac))


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
    shifts_m: Sequence[float] = (),
    shift_penalty: float = 0.02,
    positions: Sequence[float] = (0.5,),
    position_penalty: float = 0.02,
    on_progress: Callable[[int, int], None] | None = None,
    executor: Executor | None = None,
    prior: Sequence[Protrusion] = (),
    min_rows: int = 1,
) -> ProxyFit:
    """Fit the centre-of-mass shift and the protrusion depth (and, opt-in, its position
    along x) of each face of `object_id` to its real rows, jointly.

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
        shifts_m: Candidate centre-of-mass shifts along x (m); 0 (uniform density, the
            prior) is added. Empty: the mass distribution is not searched.
        shift_penalty: Brier-score penalty at the largest |shift| (linear in |shift|).
        positions: Candidate protrusion positions along x, fractions of the object's
            length in 0..1; 0.5 (the centre, the prior) is added. Only 0.5 (the default):
            the position is not searched, as before.
        position_penalty: Brier-score penalty at the largest |position - 0.5| (linear).
        on_progress: Called with (done, total) experiments.
        executor: Runs the experiments instead of `workers` local processes (e.g. a
            started `RayExecutor`; candidate files in `work_dir` must then be readable
            where the experiments run).
        prior: Each face's prior feature (at most one per face; empty: the plain body).
            With a prior the positions are not searched.
        min_rows: Real rows a face needs before its depth is searched; a face with fewer
            keeps its prior (1: every face tried is searched, as before).
    """
    mine = [r for r in rows if str(r["object_id"]) == object_id]
    if not mine:
        raise InputError(f"no real rows of object {object_id!r}")
    check_real_rows(mine, f"rows of {object_id}")
    if "experiment_id" not in mine[0]:
        raise InputError("the real table needs an experiment_id column")
    if runs < 1:
        raise InputError(f"runs must be at least 1, got {runs}")
    if isinstance(min_rows, bool) or not isinstance(min_rows, int) or min_rows < 1:
        raise InputError(f"min_rows must be an integer of at least 1, got {min_rows!r}")
    priors = {p.face: p for p in prior}
    if len(priors) != len(prior):
        raise InputError(f"prior of {object_id}: at most one feature per face")
    depths = np.unique(np.r_[0.0, np.asarray(depths_m, dtype=float)])
    shifts = _shift_grid(shifts_m)
    check_positions(positions)
    xs = _position_grid(positions)
    searched = len(xs) > 1
    if searched and priors:
        raise InputError("protrusion positions are not searched around a prior feature")
    base = base or object_id
    check_shifts(base, shifts)  # InputError now, not in a worker
    body = _base_model(base)
    work_dir.mkdir(parents=True, exist_ok=True)
    tried = sorted({str(r["face"]) for r in mine})
    by_face = {f: [r for r in mine if r["face"] == f] for f in tried}
    face_rows = {f: rs for f, rs in by_face.items() if len(rs) >= min_rows}  # searched
    faces = list(face_rows)
    kept = tuple(p for f, p in sorted(priors.items()) if f not in face_rows)
    mine = [r for rs in face_rows.values() for r in rs]
    grids = {f: _prior_grid(depths, priors[f]) if f in priors else _face_grid(depths, xs)
             for f in faces}  # fmt: skip
    specs, where = [], {}
    for face in faces:
        grid_d, grid_x = grids[face]
        for j, shift in enumerate(shifts):
            for k, (depth, x) in enumerate(zip(grid_d, grid_x, strict=True)):
                name, ref = _candidate(work_dir, object_id, base, face, float(depth),
                                       float(shift), float(x), priors.get(face))  # fmt: skip
                for run in range(runs):
                    batch = replay_specs(face_rows[face], scene=scene, run=run, seed=seed,
                                         object_map={object_id: ref})  # fmt: skip
                    for i, s in enumerate(batch):
                        where[(name, s.run, s.seed)] = (face, j, k, i)
                    specs += batch
    wins = {f: np.zeros((len(shifts), len(grids[f][0]), len(face_rows[f]))) for f in faces}
    for done, row in enumerate(run_rows(specs, workers, executor), start=1):
        face, j, k, i = where[(str(row["object_id"]), int(row["run"]), int(row["seed"]))]
        wins[face][j, k, i] += 1 if row["status"] == "ok" and row["success"] == 1 else 0
        if on_progress is not None:
            on_progress(done, len(specs))
    masks, preds, start = {}, {}, 0
    for face in faces:  # the object's rows, face by face
        n_face = len(face_rows[face])
        masks[face] = np.zeros(len(mine), dtype=bool)
        masks[face][start : start + n_face] = True
        preds[face] = np.full((len(shifts), len(grids[face][0]), len(mine)), np.nan)
        preds[face][:, :, masks[face]] = wins[face] / runs
        start += n_face
    y = np.array([int(r["success"]) for f in faces for r in face_rows[f]])
    at = {f: grids[f][1] for f in faces} if searched else None
    joint = JointCandidates(shifts, {f: grids[f][0] for f in faces}, preds, masks, at)
    chosen = (choose_joint(joint, y, np.arange(len(y)), penalty, shift_penalty, position_penalty)
              if faces else {"shift": 0})  # fmt: skip
    fits = []
    for face in faces:
        ids = np.array([int(r["experiment_id"]) for r in face_rows[face]])
        grid_d, grid_x = grids[face]
        fits.append(FaceFit(face, grid_d, wins[face] / runs, ids, y[masks[face]], chosen[face],
                            grid_x if searched else None))  # fmt: skip
    shift = float(shifts[chosen["shift"]])
    protrusions = tuple(
        sorted(
            (*kept, *(_chosen_feature(f, priors.get(f.face)) for f in fits)),
            key=lambda p: p.face,
        )
    )
    spec = ProxySpec(object_id, base, protrusions, com_shift_m=shift)
    split = mass_split(body, spec)
    return ProxyFit(spec, tuple(fits), shifts, chosen["shift"], split.front_fraction,
                    split.uniform_front_fraction)  # fmt: skip


def _chosen_feature(fit: FaceFit, prior: Protrusion | None) -> Protrusion:
    """The chosen candidate of a face as a feature: the prior's shape at the chosen depth,
    or a centred protrusion (at the searched position) without a prior."""
    depth = float(fit.depths_m[fit.chosen])
    if prior is not None:
        return dataclasses.replace(prior, depth_m=depth)
    x = 0.5 if fit.positions is None else float(fit.positions[fit.chosen])
    return Protrusion(fit.face, depth, x_frac=x)


def candidates_path(folder: Path, object_id: str) -> Path:
    """Where `calibrate object` keeps the candidates of `object_id` in `folder`."""
    return folder / f"{object_id}.candidates.npz"


def save_candidates(fit: ProxyFit, path: Path) -> Path:
    """The candidates' predictions as .npz (read back by `load_candidates`): per face the
    depths, P (S, K, n_face), the experiment ids and the chosen depth (and, with searched
    positions, each candidate's position); the shifts (S,) and the chosen shift."""
    arrays = {"shifts_m": fit.shifts_m, "shift_chosen": np.array(fit.shift_chosen)}
    for f in fit.faces:
        arrays[f"{f.face}_depths_m"] = f.depths_m
        arrays[f"{f.face}_p"] = f.probabilities
        arrays[f"{f.face}_ids"] = f.experiment_ids
        arrays[f"{f.face}_chosen"] = np.array(f.chosen)
        if f.positions is not None:
            arrays[f"{f.face}_positions"] = f.positions
    np.savez(path, object_id=np.array(fit.spec.object_id), **arrays)
    return path


def load_candidates(
    path: Path, experiment_ids: np.ndarray
) -> dict[str, tuple[np.ndarray | JointCandidates, np.ndarray]]:
    """Candidates aligned with `experiment_ids` (n,), and the rows they cover (n,) bool.

    A file with a shift grid (`calibrate object` since it searches the mass distribution)
    gives one entry, the object id → `JointCandidates`. An older file (depths only) gives
    'object:face' → candidate predictions (k, n), NaN on other rows. InputError if a fitted
    row is missing.
    """
    pos = {int(e): j for j, e in enumerate(experiment_ids)}
    n = len(experiment_ids)
    with np.load(path) as data:
        obj = str(data["object_id"])
        joint = "shifts_m" in data
        out: dict[str, tuple[np.ndarray | JointCandidates, np.ndarray]] = {}
        preds, masks, depths, positions = {}, {}, {}, {}
        for face in ("front", "back"):
            if f"{face}_p" not in data:
                continue
            p, ids = data[f"{face}_p"], data[f"{face}_ids"]
            if any(int(e) not in pos for e in ids):
                raise InputError(f"{path}: fitted rows missing from the real table")
            cols = [pos[int(e)] for e in ids]
            full = np.full((*p.shape[:-1], n), np.nan)
            full[..., cols] = p
            mask = np.zeros(n, dtype=bool)
            mask[cols] = True
            preds[face], masks[face], depths[face] = full, mask, data[f"{face}_depths_m"]
            if f"{face}_positions" in data:
                positions[face] = data[f"{face}_positions"]
            if not joint:
                out[f"{obj}:{face}"] = (full, mask)
        if joint and preds:
            cover = np.any(np.vstack(list(masks.values())), axis=0)
            at = positions or None  # files without positions: every candidate centred
            joint_c = JointCandidates(np.asarray(data["shifts_m"]), depths, preds, masks, at)
            out[obj] = (joint_c, cover)
    return out


def fitted_candidates(
    folder: Path, rows: Sequence[Mapping[str, object]]
) -> tuple[dict[str, np.ndarray | JointCandidates], np.ndarray]:
    """Candidate predictions per group for `rows` from the `calibrate object` outputs in
    `folder`, and each row's group (n,): the object id for an object fitted with its mass
    distribution (`JointCandidates`), 'object:face' for older per-face fits. InputError if
    anything is missing."""
    ids = np.array([int(r["experiment_id"]) for r in rows])
    candidates: dict[str, np.ndarray | JointCandidates] = {}
    covered = np.zeros(len(rows), dtype=bool)
    for obj in sorted({str(r["object_id"]) for r in rows}):
        path = candidates_path(folder, obj)
        if not path.is_file():
            raise InputError(f"{path}: missing; run 'transfertwin calibrate object --object {obj}'")
        for group, (pred, mask) in load_candidates(path, ids).items():
            candidates[group] = pred
            covered |= mask
    objects = np.array([str(r["object_id"]) for r in rows])
    faces = np.array([f"{r['object_id']}:{r['face']}" for r in rows])
    groups = np.where(np.isin(objects, list(candidates)), objects, faces)
    missing = sorted(set(faces[~covered]))
    if missing:
        raise InputError(f"{folder}: no fitted candidates for {', '.join(missing)}")
    return candidates, groups
