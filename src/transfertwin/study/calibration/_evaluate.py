"""Honest evaluation of a twin's predictions against real outcomes, beside baselines.

The twin predicts P(success) for each real experiment: the share of successful repeated
runs with placement noise, shrunk towards the training base rate by `shrink` (a share of
R = 2 runs is 0, 0.5 or 1, and a hard 0 or 1 costs an unbounded log-loss). Everything that
is tuned — which proxy object stands in for each real core, the shrinkage and the decision
threshold that turns P into a bit for F0.5 — is chosen on the training rows of each fold
only (`fold_predictions`), and the held-out rows are scored with that choice. The same
protocol scores a logistic regression on the state and docking error and the base-rate
predictor, on the same repeated stratified folds.

Shapes: `n` real rows; `y` (n,) 0/1 outcomes; probabilities (n,) in [0, 1]; candidate
predictions per object (k, n), one row per candidate proxy of that object, or a
`JointCandidates` (an object whose faces share a centre-of-mass shift: (S, K, n) per face).
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import asdict, dataclass

import numpy as np

from transfertwin._errors import InputError
from transfertwin.store import DOCKING_ERROR_COLUMNS
from transfertwin.study.calibration._metrics import ConfusionMatrix

__all__ = [
    "HYBRID_CS",
    "Evaluation",
    "JointCandidates",
    "Scores",
    "best_threshold",
    "choose_candidates",
    "choose_joint",
    "cv_splits",
    "evaluate_predictions",
    "fold_predictions",
    "hybrid_features",
    "hybrid_fold_predictions",
    "hybrid_probabilities",
    "in_sample",
    "logistic_features",
    "logistic_probabilities",
    "score",
    "shrink",
]

_EPS = 1e-6


@dataclass(frozen=True)
class Scores:
    """Metrics of probabilistic predictions at one threshold (App. A.2 for the bits)."""

    f05: float
    precision: float
    recall: float
    accuracy: float
    brier: float
    log_loss: float
    threshold: float

    def to_dict(self) -> dict[str, float]:
        """Plain floats for JSON."""
        return asdict(self)


def score(p: np.ndarray, y: np.ndarray, threshold: float) -> Scores:
    """F0.5, precision, recall, accuracy at `threshold` (success iff p >= threshold), and the
    Brier score and log-loss of the probabilities (clipped to [1e-6, 1 - 1e-6])."""
    p, y = np.asarray(p, dtype=float), np.asarray(y, dtype=int)
    cm = ConfusionMatrix.from_predictions(p >= threshold, y.astype(bool))
    brier, loss = _probability_scores(p, y)
    return Scores(cm.f05, cm.precision, cm.recall, cm.accuracy, brier, loss, float(threshold))


def _probability_scores(p: np.ndarray, y: np.ndarray) -> tuple[float, float]:
    """Brier score and log-loss (probabilities clipped to [1e-6, 1 - 1e-6])."""
    q = np.clip(p, _EPS, 1 - _EPS)
    loss = -float(np.mean(y * np.log(q) + (1 - y) * np.log(1 - q)))
    return float(np.mean((p - y) ** 2)), loss


def best_threshold(p: np.ndarray, y: np.ndarray) -> float:
    """The threshold in (0, 1] that maximises F0.5 of `p` against `y`.

    Candidates are the distinct predicted values (predict success iff p >= t); ties go to
    the lowest threshold, so a constant predictor says 'success' (the base-rate choice).
    """
    p, y = np.asarray(p, dtype=float), np.asarray(y, dtype=int)
    ts = np.unique(np.clip(p, _EPS, 1.0))
    if len(ts) == 0:
        return 1.0
    # counts of 'p >= t' for every candidate t at once (sorted, cumulative from the top)
    order = np.argsort(p, kind="stable")
    ps, ys = p[order], y[order]
    start = np.searchsorted(ps, ts, side="left")  # first row with p >= t
    pos_above = np.concatenate([np.cumsum(ys[::-1])[::-1], [0]])
    tp = pos_above[start].astype(float)
    fp = (len(p) - start) - tp
    fn = ys.sum() - tp
    den = 1.25 * tp + 0.25 * fn + fp
    f = np.divide(1.25 * tp, den, out=np.zeros_like(tp), where=den > 0)
    best_t, best_f = 1.0, -1.0
    for t, value in zip(ts.tolist(), f.tolist(), strict=True):
        if value > best_f + 1e-12:
            best_t, best_f = float(t), value
    return best_t


def shrink(p: np.ndarray, y: np.ndarray, train: np.ndarray) -> np.ndarray:
    """Simulated shares shrunk towards the base rate of the `train` rows.

    ``(1 - w) * p + w * mean(y[train])`` with the weight w in 0, 0.05, …, 0.6 that gives
    the lowest log-loss on the training rows. The map is monotone, so the order of the
    rows — and with it the best F0.5 over thresholds — does not change.
    """
    p, y = np.asarray(p, dtype=float), np.asarray(y, dtype=int)
    rate = float(y[train].mean())
    weights = np.linspace(0.0, 0.6, 13)
    losses = [_probability_scores((1 - w) * p[train] + w * rate, y[train])[1] for w in weights]
    w = float(weights[int(np.argmin(losses))])
    return (1 - w) * p + w * rate


def cv_splits(
    y: np.ndarray, folds: int, repeats: int, seed: int
) -> list[tuple[np.ndarray, np.ndarray]]:
    """(train, test) index pairs of repeated stratified K-fold; repeat r is splits
    r*folds .. (r+1)*folds - 1 and covers every row once as test."""
    y = np.asarray(y, dtype=int)
    if folds < 2:
        raise InputError(f"--folds must be at least 2, got {folds}")
    if repeats < 1:
        raise InputError(f"--repeats must be at least 1, got {repeats}")
    if min(np.bincount(y, minlength=2)) < folds:
        raise InputError(f"each outcome needs at least {folds} rows for {folds} folds")
    from sklearn.model_selection import RepeatedStratifiedKFold  # ~1 s: only when evaluating

    rskf = RepeatedStratifiedKFold(n_splits=folds, n_repeats=repeats, random_state=seed)
    return list(rskf.split(np.zeros(len(y)), y))


@dataclass(frozen=True, eq=False)
class JointCandidates:
    """Candidate proxies of one object: a centre-of-mass shift shared by its faces and a
    protrusion depth per face, searched jointly.

    Attributes:
        shifts_m: Candidate shifts (S,), the prior 0 first.
        depths_m: Face → candidate depths (K,), the prior 0 first.
        faces: Face → predictions (S, K, n) for all n rows (NaN off that face's rows).
        masks: Face → that face's rows (n,) bool.
        positions: Face → each candidate's protrusion position along x (K,), a fraction of
            the object's length (0.5 the centre), when positions were searched; then a depth
            repeats once per position and the depth penalty counts distinct depths. None:
            every candidate is centred (one candidate per depth).
    """

    shifts_m: np.ndarray
    depths_m: Mapping[str, np.ndarray]
    faces: Mapping[str, np.ndarray]
    masks: Mapping[str, np.ndarray]
    positions: Mapping[str, np.ndarray] | None = None

    def predictions(self, chosen: Mapping[str, int]) -> np.ndarray:
        """Predictions (n,) of the chosen candidate (NaN off this object's rows)."""
        n = len(next(iter(self.masks.values())))
        p = np.full(n, np.nan)
        for face, pred in self.faces.items():
            mask = self.masks[face]
            p[mask] = pred[chosen["shift"], chosen[face], mask]
        return p


def _shape_cost(
    cands: JointCandidates, face: str, k: int, penalty: float, position_penalty: float
) -> np.ndarray | float:
    """Penalty (K,) of a face's candidates: `penalty` times the depth's rank among the
    distinct depths / (D - 1), plus with positions `position_penalty * |x - 0.5| / max`."""
    if cands.positions is None:
        return penalty * np.arange(k) / max(k - 1, 1)
    depths = np.asarray(cands.depths_m[face], dtype=float)
    distinct, rank = np.unique(depths, return_inverse=True)
    cost = penalty * rank / max(len(distinct) - 1, 1)
    off = np.abs(np.asarray(cands.positions[face], dtype=float) - 0.5)
    if off.max() > 0:
        cost = cost + position_penalty * off / off.max()
    return cost


def choose_joint(
    cands: JointCandidates,
    y: np.ndarray,
    rows: np.ndarray,
    penalty: float = 0.0,
    shift_penalty: float = 0.0,
    position_penalty: float = 0.0,
) -> dict[str, int]:
    """The shift and the depth (and position) per face with the lowest penalised Brier score
    on `rows`.

    The objective of shift s is the sum over faces, weighted by their share of the object's
    rows among `rows`, of min over candidate k of (Brier score of the face's rows +
    `penalty * k / (K - 1)`), plus `shift_penalty * |s| / max |s|` (regularisation towards
    the uniform-density prior). With searched positions (`JointCandidates.positions`) k's
    depth penalty uses its depth's rank among the distinct depths instead of k, and
    `position_penalty * |x - 0.5| / max |x - 0.5|` pulls towards the centre. For a fixed
    shift each face's choice is the per-face choice of `choose_candidates`. Ties go to the
    earlier candidate (the prior first).

    Returns:
        {'shift': index into `shifts_m`, face: candidate index} (all 0 without rows).
    """
    y = np.asarray(y, dtype=int)
    shifts = np.asarray(cands.shifts_m, dtype=float)
    sizes = {f: int(m[rows].sum()) for f, m in cands.masks.items()}
    total = sum(sizes.values())
    if total == 0:
        return {"shift": 0, **{f: 0 for f in cands.faces}}
    reach = float(np.abs(shifts).max()) or 1.0
    objective = shift_penalty * np.abs(shifts) / reach
    best: dict[str, np.ndarray] = {}
    for face, pred in cands.faces.items():
        mine = rows[cands.masks[face][rows]]
        if len(mine) == 0:
            best[face] = np.zeros(len(shifts), dtype=int)
            continue
        k = pred.shape[1]
        cost = np.mean((pred[:, :, mine] - y[mine]) ** 2, axis=2)  # (S, K)
        cost = cost + _shape_cost(cands, face, k, penalty, position_penalty)
        best[face] = np.argmin(cost, axis=1)
        objective = objective + sizes[face] / total * cost.min(axis=1)
    s = int(np.argmin(objective))
    return {"shift": s, **{f: int(best[f][s]) for f in cands.faces}}


def choose_candidates(
    candidates: Mapping[str, np.ndarray | JointCandidates],
    objects: np.ndarray,
    y: np.ndarray,
    rows: np.ndarray,
    penalty: float = 0.0,
    shift_penalty: float = 0.0,
    position_penalty: float = 0.0,
) -> dict[str, int | dict[str, int]]:
    """Per object, the candidate proxy with the lowest Brier score on `rows` of that object.

    Args:
        candidates: Object id → predictions (k, n) of its k candidate proxies for all rows;
            candidate 0 is the family prior, later ones move away from it. Or a
            `JointCandidates` (chosen by `choose_joint`).
        objects: Object id per row (n,).
        y: Real outcomes (n,).
        rows: The row indices the choice may look at (a training fold).
        penalty: Regularisation towards the prior: `penalty * k / (K - 1)` is added to
            candidate k's Brier score (0: none).
        shift_penalty: Regularisation of a joint candidate's centre-of-mass shift.
        position_penalty: Regularisation of a joint candidate's protrusion position.

    Returns:
        Object id → chosen candidate index (a `choose_joint` dict for joint candidates).
    """
    chosen: dict[str, int | dict[str, int]] = {}
    for obj, pred in candidates.items():
        if isinstance(pred, JointCandidates):
            chosen[obj] = choose_joint(pred, y, rows, penalty, shift_penalty, position_penalty)
            continue
        mine = rows[objects[rows] == obj]
        if len(mine) == 0:
            chosen[obj] = 0
            continue
        brier = np.mean((pred[:, mine] - y[mine]) ** 2, axis=1)
        k = pred.shape[0]
        brier = brier + penalty * np.arange(k) / max(k - 1, 1)
        chosen[obj] = int(np.argmin(brier))
    return chosen


def _assemble(
    candidates: Mapping[str, np.ndarray | JointCandidates],
    objects: np.ndarray,
    chosen: Mapping[str, int | dict[str, int]],
) -> np.ndarray:
    p = np.full(len(objects), np.nan)
    for obj, k in chosen.items():
        cands = candidates[obj]
        if isinstance(cands, JointCandidates):
            q = cands.predictions(k)
            p[~np.isnan(q)] = q[~np.isnan(q)]
            continue
        mask = objects == obj
        p[mask] = cands[k, mask]
    if np.isnan(p).any():
        missing = sorted(set(objects[np.isnan(p)]))
        raise InputError(f"no twin predictions for object(s) {', '.join(missing)}")
    return p


def fold_predictions(
    candidates: Mapping[str, np.ndarray | JointCandidates],
    objects: np.ndarray,
    y: np.ndarray,
    splits: Sequence[tuple[np.ndarray, np.ndarray]],
    penalty: float = 0.0,
    shift_penalty: float = 0.0,
    position_penalty: float = 0.0,
) -> list[tuple[np.ndarray, np.ndarray, float, dict[str, int | dict[str, int]]]]:
    """Per split: (test rows, their predictions, threshold, chosen candidates), where the
    candidates and the threshold are chosen on the training rows only."""
    out = []
    for train, test in splits:
        chosen = choose_candidates(
            candidates, objects, y, train, penalty, shift_penalty, position_penalty
        )
        p = shrink(_assemble(candidates, objects, chosen), y, train)
        out.append((test, p[test], best_threshold(p[train], y[train]), chosen))
    return out


def in_sample(
    candidates: Mapping[str, np.ndarray | JointCandidates],
    objects: np.ndarray,
    y: np.ndarray,
    penalty: float,
    shift_penalty: float = 0.0,
    position_penalty: float = 0.0,
) -> tuple[np.ndarray, float, dict[str, int | dict[str, int]]]:
    """Predictions, threshold and candidates chosen on all rows (the optimistic figure)."""
    rows = np.arange(len(y))
    chosen = choose_candidates(
        candidates, objects, y, rows, penalty, shift_penalty, position_penalty
    )
    p = shrink(_assemble(candidates, objects, chosen), y, rows)
    return p, best_threshold(p, y), chosen


def logistic_features(rows: Sequence[Mapping[str, object]]) -> np.ndarray:
    """Features of the logistic baseline, (n, d): one-hot object, face, conveyor and
    object×face; sin/cos of θ and 2θ per object×face; the docking error (mm, mm, deg)."""
    objs = sorted({str(r["object_id"]) for r in rows})
    groups = [(o, f) for o in objs for f in ("front", "back")]
    feats = []
    for r in rows:
        o, f, c = str(r["object_id"]), str(r["face"]), str(r["conveyor"])
        th = math.radians(float(r["theta_deg"]))
        x = [float(o == k) for k in objs]
        x += [float(f == "back")]
        x += [float(c == k) for k in ("left", "right")]
        trig = [math.sin(th), math.cos(th), math.sin(2 * th), math.cos(2 * th)]
        for g in groups:
            on = float((o, f) == g)
            x += [on, *(on * v for v in trig)]
        x += [float(r[k]) for k in DOCKING_ERROR_COLUMNS]
        feats.append(x)
    return np.asarray(feats, dtype=float)


def logistic_probabilities(
    X: np.ndarray, y: np.ndarray, train: np.ndarray, C: float = 1.0
) -> np.ndarray:
    """P(success) of every row from a logistic regression fitted on `train` rows
    (standardised features, L2 penalty `C`)."""
    from sklearn.linear_model import LogisticRegression
    from sklearn.pipeline import make_pipeline
    from sklearn.preprocessing import StandardScaler

    model = make_pipeline(StandardScaler(), LogisticRegression(C=C, max_iter=2000))
    model.fit(X[train], y[train])
    return model.predict_proba(X)[:, 1]


def hybrid_features(p_sim: np.ndarray, X: np.ndarray) -> np.ndarray:
    """Features of the hybrid: the twin's simulated success share per row beside the
    logistic baseline's features, (n, 1 + d)."""
    return np.column_stack([np.asarray(p_sim, dtype=float), X])


#: L2 strengths C the hybrid chooses from (inner cross-validation on the training rows).
HYBRID_CS = (0.03, 0.1, 0.3, 1.0)


def hybrid_probabilities(Z: np.ndarray, y: np.ndarray, train: np.ndarray) -> np.ndarray:
    """P(success) of every row from the hybrid's logistic regression on `train` rows, its
    L2 strength C chosen from `HYBRID_CS` by the log-loss of a 3-fold stratified inner
    cross-validation on those rows only (the hybrid has one more feature than the baseline
    and overfits at C = 1)."""
    y_train = y[train]
    folds = min(3, int(np.bincount(y_train, minlength=2).min()))
    best_c = 1.0
    if folds >= 2:
        from sklearn.model_selection import StratifiedKFold

        inner = StratifiedKFold(n_splits=folds, shuffle=True, random_state=0)
        losses = []
        for c in HYBRID_CS:
            loss = 0.0
            for fit, val in inner.split(np.zeros(len(train)), y_train):
                q = logistic_probabilities(Z[train], y_train, fit, C=c)[val]
                loss += _probability_scores(q, y_train[val])[1] * len(val)
            losses.append(loss)
        best_c = HYBRID_CS[int(np.argmin(losses))]
    return logistic_probabilities(Z, y, train, C=best_c)


def hybrid_fold_predictions(
    candidates: Mapping[str, np.ndarray | JointCandidates],
    objects: np.ndarray,
    y: np.ndarray,
    X: np.ndarray,
    splits: Sequence[tuple[np.ndarray, np.ndarray]],
    penalty: float = 0.0,
    shift_penalty: float = 0.0,
    position_penalty: float = 0.0,
) -> list[tuple[np.ndarray, np.ndarray, float]]:
    """Per split: (test rows, their predictions, threshold) of the hybrid, a residual
    classifier — a logistic regression on the twin's output (P_sim, the simulated share of
    the candidate proxies chosen on the training rows) and the baseline's features `X`.

    Everything is fitted on the training rows only: the candidate choice, the regression
    with its regularisation (`hybrid_probabilities`) and the threshold. (The training rows'
    P_sim comes from candidates chosen on those same rows, which makes it look a little
    better there than on the test rows; the held-out score stays honest.)
    """
    out = []
    for train, test in splits:
        chosen = choose_candidates(
            candidates, objects, y, train, penalty, shift_penalty, position_penalty
        )
        Z = hybrid_features(_assemble(candidates, objects, chosen), X)
        q = hybrid_probabilities(Z, y, train)
        out.append((test, q[test], best_threshold(q[train], y[train])))
    return out


def _pooled(
    parts: Sequence[tuple[np.ndarray, np.ndarray, float]], y: np.ndarray, n: int
) -> tuple[dict[str, float], np.ndarray, np.ndarray]:
    """Metrics of out-of-fold predictions of one repeat (each fold with its own threshold)."""
    p, bits = np.full(n, np.nan), np.zeros(n, dtype=bool)
    for test, pt, thr in parts:
        p[test], bits[test] = pt, pt >= thr
    cm = ConfusionMatrix.from_predictions(bits, y.astype(bool))
    brier, loss = _probability_scores(p, y)
    return {
        "f05": cm.f05, "precision": cm.precision, "recall": cm.recall,
        "accuracy": cm.accuracy, "brier": brier, "log_loss": loss,
    }, p, bits  # fmt: skip


def _mean_std(per_repeat: Sequence[dict[str, float]]) -> dict[str, float]:
    out: dict[str, float] = {}
    for key in per_repeat[0]:
        values = np.array([r[key] for r in per_repeat])
        out[key] = float(values.mean())
        out[f"{key}_std"] = float(values.std(ddof=1)) if len(values) > 1 else 0.0
    return out


@dataclass(frozen=True)
class Evaluation:
    """Figures of the twin and the baselines on the same rows and folds.

    Attributes:
        figures: 'base_rate', 'logistic_in_sample', 'logistic_cv', 'twin_in_sample',
            'twin_cv', and beside them (never instead) 'hybrid_cv' and 'hybrid_in_sample':
            metric → value ('*_std' over repeats for the CV figures).
        per_object: Object id → confusion matrices (in-sample and first-repeat CV) and
            counts.
        twin_p, twin_oof, logistic_oof, hybrid_oof: Predictions (n,): the twin in-sample and
            the models out-of-fold in the first repeat.
        chosen: The candidates chosen on all rows (in-sample).
    """

    n: int
    successes: int
    folds: int
    repeats: int
    figures: dict[str, dict[str, float]]
    per_object: dict[str, dict[str, object]]
    twin_p: np.ndarray
    twin_oof: np.ndarray
    logistic_oof: np.ndarray
    chosen: dict[str, int | dict[str, int]]
    hybrid_oof: np.ndarray


def evaluate_predictions(
    rows: Sequence[Mapping[str, object]],
    candidates: Mapping[str, np.ndarray],
    *,
    folds: int = 5,
    repeats: int = 5,
    seed: int = 0,
    penalty: float = 0.0,
    groups: np.ndarray | None = None,
    shift_penalty: float = 0.0,
    position_penalty: float = 0.0,
) -> Evaluation:
    """Score the twin (from candidate predictions per group) against the base-rate and
    logistic baselines, in-sample and in repeated stratified K-fold cross-validation, and
    beside it the hybrid (`hybrid_fold_predictions`).

    In every fold the twin's candidates, its threshold and the logistic model and its
    threshold are fitted on the training rows only. `groups` (n,) names the candidate set
    of each row (default: its object id; e.g. 'o1:back' for per-face proxies).
    """
    y = np.array([int(r["success"]) for r in rows])
    objects = np.array([str(r["object_id"]) for r in rows])
    units = objects if groups is None else np.asarray(groups)
    splits = cv_splits(y, folds, repeats, seed)
    X = logistic_features(rows)
    folded = fold_predictions(
        candidates, units, y, splits, penalty, shift_penalty, position_penalty
    )
    twin_parts = [(test, p, thr) for test, p, thr, _ in folded]
    hybrid_parts = hybrid_fold_predictions(candidates, units, y, X, splits, penalty,
                                           shift_penalty, position_penalty)  # fmt: skip
    logit_parts = []
    for train, test in splits:
        q = logistic_probabilities(X, y, train)
        logit_parts.append((test, q[test], best_threshold(q[train], y[train])))
    twin_rep, logit_rep, hybrid_rep, oof = [], [], [], {}
    for r in range(repeats):
        block = slice(r * folds, (r + 1) * folds)
        m, p_t, b_t = _pooled(twin_parts[block], y, len(y))
        twin_rep.append(m)
        m2, p_l, _ = _pooled(logit_parts[block], y, len(y))
        logit_rep.append(m2)
        m3, p_h, _ = _pooled(hybrid_parts[block], y, len(y))
        hybrid_rep.append(m3)
        if r == 0:
            oof = {"twin": p_t, "twin_bits": b_t, "logistic": p_l, "hybrid": p_h}
    p_in, thr_in, chosen_in = in_sample(
        candidates, units, y, penalty, shift_penalty, position_penalty
    )
    q_in = logistic_probabilities(X, y, np.arange(len(y)))
    h_in = hybrid_probabilities(
        hybrid_features(_assemble(candidates, units, chosen_in), X), y, np.arange(len(y))
    )
    base = np.full(len(y), y.mean())
    figures = {
        "base_rate": score(base, y, best_threshold(base, y)).to_dict(),
        "logistic_in_sample": score(q_in, y, best_threshold(q_in, y)).to_dict(),
        "logistic_cv": _mean_std(logit_rep),
        "twin_in_sample": score(p_in, y, thr_in).to_dict(),
        "twin_cv": _mean_std(twin_rep),
        "hybrid_in_sample": score(h_in, y, best_threshold(h_in, y)).to_dict(),
        "hybrid_cv": _mean_std(hybrid_rep),
    }
    per_object = {}
    for obj in sorted(set(objects)):
        mask = objects == obj
        per_object[obj] = {
            "n": int(mask.sum()), "real_successes": int(y[mask].sum()),
            "twin_mean_p": float(p_in[mask].mean()),
            "in_sample": ConfusionMatrix.from_predictions(p_in[mask] >= thr_in,
                                                          y[mask].astype(bool)).to_dict(),
            "cv": ConfusionMatrix.from_predictions(oof["twin_bits"][mask],
                                                   y[mask].astype(bool)).to_dict(),
        }  # fmt: skip
    return Evaluation(len(y), int(y.sum()), folds, repeats, figures, per_object, p_in,
                      oof["twin"], oof["logistic"], chosen_in, oof["hybrid"])  # fmt: skip
