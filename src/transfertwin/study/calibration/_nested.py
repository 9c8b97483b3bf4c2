"""Nested cross-validation of the twin beside statistical baselines: every choice inside
the training rows, over many CV seeds, and held-out cells.

The twin comes as one or more *variants* (candidate folders of `calibrate object`: scene
variants such as pulley shape and radius, runs per row, contact settings; each with its
cached per-row simulated shares of every candidate proxy). In every outer training fold:

1. the variant and the depth penalty are chosen by an inner stratified K-fold on the
   training rows alone (the lowest inner Brier score of `fold_predictions`, i.e. with the
   candidates, shrinkage and threshold re-chosen inside every inner fold);
2. with that choice the candidates, the shrinkage and the decision threshold are chosen on
   the training rows (`fold_predictions`) and the test rows are scored.

Nothing is simulated here: every choice picks among cached per-row probabilities. The same
outer folds score the (object, face) rate table, the (object, face, conveyor) rate table
shrunk towards it (`shrunk_rate_table`), the logistic regression (its L2 strength chosen by
an inner CV, `hybrid_probabilities` on the logistic features) and always-success; each
predictor's threshold is chosen on its training rows. One CV seed is one stratified K-fold
partition; S seeds give (S, n) held-out predictions per predictor.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from transfertwin._errors import InputError
from transfertwin.study.calibration._baselines import cell_keys, rate_table, shrunk_rate_table
from transfertwin.study.calibration._evaluate import (
    JointCandidates,
    _assemble,
    best_threshold,
    cv_splits,
    fold_predictions,
    hybrid_probabilities,
    logistic_features,
)

__all__ = ["PREDICTORS", "HeldOut", "Variant", "held_out", "leave_cell_out", "select_variant"]

#: The predictors scored on the same folds, the twin first.
PREDICTORS: tuple[str, ...] = (
    "twin", "table_object_face", "table_object_face_conveyor", "logistic", "always_success",
)  # fmt: skip

Progress = Callable[[int, int], None]


@dataclass(frozen=True, eq=False)
class Variant:
    """One candidate folder: its label, candidate predictions per group and each row's
    group (as `fitted_candidates` returns them)."""

    label: str
    candidates: Mapping[str, np.ndarray | JointCandidates]
    groups: np.ndarray


@dataclass(frozen=True, eq=False)
class HeldOut:
    """Held-out predictions of every predictor.

    Attributes:
        p: Predictor → probabilities (S, n), one row per CV seed (or one row for held-out
            cells).
        bits: Predictor → decisions (S, n) (p >= the threshold of the row's training fold).
        twin_raw: The twin's unshrunk simulated share (S, n) of the candidates chosen in
            the row's training fold.
        chosen: (variant label, penalty) → how many outer folds chose it.
        folds: Outer folds per seed (the number of cells for held-out cells).
    """

    p: dict[str, np.ndarray]
    bits: dict[str, np.ndarray]
    twin_raw: np.ndarray
    chosen: dict[tuple[str, float], int]
    folds: int


def _stratified(y: np.ndarray, rows: np.ndarray, k: int, seed: int) -> list[tuple]:
    """(train, test) global indices of a stratified K-fold of `rows` (fewer folds if a class
    is too small; [] if one class has < 2 rows)."""
    from sklearn.model_selection import StratifiedKFold

    k = min(k, int(np.bincount(y[rows], minlength=2).min()))
    if k < 2:
        return []
    skf = StratifiedKFold(n_splits=k, shuffle=True, random_state=seed)
    return [(rows[a], rows[b]) for a, b in skf.split(np.zeros(len(rows)), y[rows])]


def select_variant(
    variants: Sequence[Variant],
    y: np.ndarray,
    train: np.ndarray,
    penalties: Sequence[float],
    *,
    inner_folds: int = 3,
    seed: int = 0,
    shift_penalty: float = 0.0,
    position_penalty: float = 0.0,
) -> tuple[int, float]:
    """(variant index, penalty) with the lowest Brier score of an inner stratified K-fold
    on the `train` rows (candidates, shrinkage and threshold re-chosen per inner fold);
    ties go to the earlier variant and penalty. With one option it is returned unscored."""
    options = [(v, pen) for v in range(len(variants)) for pen in penalties]
    if len(options) == 1:
        return options[0]
    inner = _stratified(y, train, inner_folds, seed)
    if not inner:
        return options[0]
    best, best_loss = options[0], np.inf
    for v, pen in options:
        var = variants[v]
        parts = fold_predictions(var.candidates, var.groups, y, inner, pen,
                                 shift_penalty, position_penalty)  # fmt: skip
        rows = np.concatenate([t for t, _, _, _ in parts])
        p = np.concatenate([q for _, q, _, _ in parts])
        loss = float(np.mean((p - y[rows]) ** 2))
        if loss < best_loss - 1e-12:
            best, best_loss = (v, pen), loss
    return best


def _fold(
    variants: Sequence[Variant], y: np.ndarray, X: np.ndarray, keys: tuple[np.ndarray, ...],
    train: np.ndarray, test: np.ndarray, settings: Mapping[str, object], seed: int,
) -> tuple[dict[str, tuple[np.ndarray, float]], np.ndarray, tuple[str, float]]:  # fmt: skip
    """Every predictor fitted on `train`: predictor → (P of the test rows, threshold), the
    twin's raw shares on the test rows and its (variant, penalty)."""
    sp, pp = float(settings["shift_penalty"]), float(settings["position_penalty"])
    v, pen = select_variant(variants, y, train, settings["penalties"],
                            inner_folds=int(settings["inner_folds"]), seed=seed,
                            shift_penalty=sp, position_penalty=pp)  # fmt: skip
    var = variants[v]
    ((_, p_twin, thr_twin, chosen),) = fold_predictions(
        var.candidates, var.groups, y, [(train, test)], pen, sp, pp
    )
    raw = _assemble(var.candidates, var.groups, chosen)[test]
    out = {"twin": (p_twin, thr_twin)}
    of, ofc = keys
    p_of = rate_table(of, y, train)
    p_ofc, _ = shrunk_rate_table(ofc, of, y, train)
    p_all = np.full(len(y), float(y[train].mean()))
    p_log = hybrid_probabilities(X, y, train) if len(set(y[train])) == 2 else p_all
    for name, p in (("table_object_face", p_of), ("table_object_face_conveyor", p_ofc),
                    ("logistic", p_log), ("always_success", p_all)):  # fmt: skip
        out[name] = (p[test], best_threshold(p[train], y[train]))
    return out, raw, (var.label, float(pen))


def _run(
    rows: Sequence[Mapping[str, object]], variants: Sequence[Variant],
    partitions: Sequence[Sequence[tuple[np.ndarray, np.ndarray]]],
    settings: Mapping[str, object], seed: int, on_progress: Progress | None,
) -> HeldOut:  # fmt: skip
    if not variants:
        raise InputError("no twin variants to evaluate")
    y = np.array([int(r["success"]) for r in rows])
    n = len(y)
    for var in variants:
        if len(var.groups) != n:
            raise InputError(f"variant {var.label}: {len(var.groups)} groups for {n} rows")
    X = logistic_features(rows)
    keys = (cell_keys(rows, ("object_id", "face")),
            cell_keys(rows, ("object_id", "face", "conveyor")))  # fmt: skip
    s = len(partitions)
    p = {k: np.full((s, n), np.nan) for k in PREDICTORS}
    bits = {k: np.zeros((s, n), dtype=bool) for k in PREDICTORS}
    raw = np.full((s, n), np.nan)
    chosen: dict[tuple[str, float], int] = {}
    total, done = sum(len(part) for part in partitions), 0
    from threadpoolctl import threadpool_limits  # a dependency of scikit-learn

    with threadpool_limits(1):  # thousands of tiny fits: BLAS threads only contend
        for i, part in enumerate(partitions):
            for f, (train, test) in enumerate(part):
                preds, raw_t, choice = _fold(variants, y, X, keys, train, test, settings,
                                             seed=1000 * (seed + i) + f)  # fmt: skip
                chosen[choice] = chosen.get(choice, 0) + 1
                raw[i, test] = raw_t
                for name, (pt, thr) in preds.items():
                    p[name][i, test], bits[name][i, test] = pt, pt >= thr
                done += 1
                if on_progress is not None:
                    on_progress(done, total)
    folds = max(len(part) for part in partitions)
    return HeldOut(p, bits, raw, dict(sorted(chosen.items())), folds)


def _settings(penalties, inner_folds, shift_penalty, position_penalty) -> dict[str, object]:
    pens = tuple(float(v) for v in penalties)
    if not pens or any(not np.isfinite(v) or v < 0 for v in pens):
        raise InputError(f"penalties must be finite and >= 0, got {list(penalties)}")
    if inner_folds < 2:
        raise InputError(f"inner folds must be at least 2, got {inner_folds}")
    return {
        "penalties": pens,
        "inner_folds": int(inner_folds),
        "shift_penalty": float(shift_penalty),
        "position_penalty": float(position_penalty),
    }


def held_out(
    rows: Sequence[Mapping[str, object]],
    variants: Sequence[Variant],
    *,
    folds: int = 5,
    seeds: int = 20,
    seed: int = 0,
    inner_folds: int = 3,
    penalties: Sequence[float] = (0.0, 0.02, 0.05),
    shift_penalty: float = 0.0,
    position_penalty: float = 0.0,
    on_progress: Progress | None = None,
) -> HeldOut:
    """Nested CV over `seeds` stratified K-fold partitions (seeds seed, seed+1, …): every
    predictor's held-out predictions (see the module doc)."""
    if seeds < 1:
        raise InputError(f"CV seeds must be at least 1, got {seeds}")
    settings = _settings(penalties, inner_folds, shift_penalty, position_penalty)
    y = np.array([int(r["success"]) for r in rows])
    partitions = [cv_splits(y, folds, 1, seed + i) for i in range(seeds)]
    return _run(rows, variants, partitions, settings, seed, on_progress)


def leave_cell_out(
    rows: Sequence[Mapping[str, object]],
    variants: Sequence[Variant],
    columns: Sequence[str],
    *,
    seed: int = 0,
    inner_folds: int = 3,
    penalties: Sequence[float] = (0.0, 0.02, 0.05),
    shift_penalty: float = 0.0,
    position_penalty: float = 0.0,
    on_progress: Progress | None = None,
) -> tuple[HeldOut, np.ndarray]:
    """Every cell of `columns` (e.g. object, face, conveyor) held out in turn, every
    predictor fitted on the other cells' rows with the nested choices; also each row's cell
    index (n,) for a cell bootstrap. A held-out cell is unseen: the rate tables fall back to
    the coarser cell (or the base rate), the twin's depth for an unseen face to its prior."""
    settings = _settings(penalties, inner_folds, shift_penalty, position_penalty)
    keys = cell_keys(rows, columns)
    cells, index = np.unique(keys, return_inverse=True)
    if len(cells) < 2:
        raise InputError(f"only one cell of {', '.join(columns)}: nothing to hold out")
    rows_all = np.arange(len(keys))
    part = [(rows_all[index != c], rows_all[index == c]) for c in range(len(cells))]
    return _run(rows, variants, [part], settings, seed, on_progress), index
