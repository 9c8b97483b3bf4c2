"""What the console shows of a calibration (Sec. 6.5, Appendix A.2): the real-vs-virtual
confusion matrix, F0.5 with a 95 % interval, and per core the success share of the real
experiments next to the twin's, each with its Clopper–Pearson interval.

Read from an output folder of `transfertwin calibrate run` (metrics.json, predictions.csv)
or `transfertwin calibrate evaluate` (evaluation.json). Pure reads; nothing is re-simulated.

The F0.5 interval is a percentile bootstrap over the real rows (`BOOTSTRAP_REPLICATES`
resamples, seed `BOOTSTRAP_SEED`): each resample draws n real rows with replacement and
recomputes the statistic the folder reports — for `calibrate run` the mean over runs of each
run's F0.5 (as in metrics.json, Table 6.4), for `calibrate evaluate` the F0.5 of the twin's
held-out predictions (first CV repeat). F0.5 depends on a prediction vector only through its
confusion matrix, so an evaluate folder's per-core matrices are all the bootstrap needs.
"""

from __future__ import annotations

import csv
import json
import math
from collections.abc import Mapping, Sequence
from pathlib import Path

import numpy as np

from transfertwin._errors import InputError
from transfertwin.study.fullstate import clopper_pearson, object_sort_key

__all__ = [
    "BOOTSTRAP_REPLICATES",
    "BOOTSTRAP_SEED",
    "MAX_LISTED_ROWS",
    "bootstrap_f05",
    "calibration_view",
    "check_calibration_dir",
    "f05_of_counts",
]

BOOTSTRAP_REPLICATES = 2000
BOOTSTRAP_SEED = 0
_MAX_JSON_BYTES = 20 * 1024 * 1024


def f05_of_counts(tp: np.ndarray, fp: np.ndarray, fn: np.ndarray) -> np.ndarray:
    """F0.5 (Eq. A.4) of arrays of counts; 0 where TP + FP + FN = 0 (as `ConfusionMatrix`)."""
    tp, fp, fn = (np.asarray(v, dtype=float) for v in (tp, fp, fn))
    den = 1.25 * tp + 0.25 * fn + fp
    return np.divide(1.25 * tp, den, out=np.zeros_like(den), where=den > 0)


def bootstrap_f05(
    predicted: np.ndarray,
    actual: np.ndarray,
    *,
    replicates: int = BOOTSTRAP_REPLICATES,
    seed: int = BOOTSTRAP_SEED,
    alpha: float = 0.05,
) -> tuple[float, float]:
    """Percentile-bootstrap interval of the mean over runs of F0.5, resampling real rows.

    Args:
        predicted: Virtual outcome per run and real row, (R, n) of 0/1.
        actual: Real outcome per row, (n,) of 0/1.
        replicates: Bootstrap resamples B.
        seed: Seed of the resampling.
        alpha: 1 - confidence level.

    Returns:
        (low, high) of the 1 - alpha interval.
    """
    pred = np.asarray(predicted, dtype=bool)
    act = np.asarray(actual, dtype=bool)
    if pred.ndim != 2 or act.ndim != 1 or pred.shape[1] != act.shape[0] or act.size == 0:
        raise InputError(f"bootstrap: predictions (R, n) and outcomes (n,) with n >= 1, got "
                         f"{pred.shape} and {act.shape}")  # fmt: skip
    rng = np.random.default_rng(seed)
    idx = rng.integers(0, act.size, size=(replicates, act.size))
    a = act[idx]
    total = np.zeros(replicates)
    for run in pred:
        p = run[idx]
        total += f05_of_counts((p & a).sum(1), (p & ~a).sum(1), (~p & a).sum(1))
    low, high = np.quantile(total / len(pred), [alpha / 2, 1 - alpha / 2])
    return float(low), float(high)


def _vector_of(confusion: Mapping[str, int]) -> tuple[np.ndarray, np.ndarray]:
    """A (1, n) prediction vector and its (n,) outcomes with this confusion matrix."""
    tp, fp, fn, tn = (int(confusion[k]) for k in ("tp", "fp", "fn", "tn"))
    pred = np.array([1] * tp + [1] * fp + [0] * fn + [0] * tn)
    act = np.array([1] * tp + [0] * fp + [1] * fn + [0] * tn)
    return pred[None, :], act


def _share(k: int, n: int) -> dict[str, object]:
    ci = clopper_pearson(k, n)
    return {"k": k, "n": n, "share": k / n if n else None,
            "low": None if math.isnan(ci.low) else ci.low,
            "high": None if math.isnan(ci.high) else ci.high}  # fmt: skip


def _shares(per_core: Mapping[str, tuple[int, int, int, int]]) -> list[dict[str, object]]:
    """Per core (k_real, n_real, k_sim, n_sim) → the share rows, cores in natural order."""
    return [{"object_id": o, "real": _share(kr, nr), "sim": _share(ks, ns)}
            for o, (kr, nr, ks, ns) in sorted(per_core.items(),
                                              key=lambda kv: object_sort_key(kv[0]))]  # fmt: skip


def _read_json(path: Path) -> dict[str, object]:
    if path.stat().st_size > _MAX_JSON_BYTES:
        raise InputError(f"{path.name}: larger than {_MAX_JSON_BYTES // 2**20} MiB")
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
    except (UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise InputError(f"{path.parent.name}/{path.name}: not JSON ({exc})") from None
    if not isinstance(data, dict):
        raise InputError(f"{path.parent.name}/{path.name}: not a JSON object")
    return data


def check_calibration_dir(folder: Path) -> str:
    """'run' or 'evaluate': which command wrote `folder`; InputError if neither."""
    if not folder.is_dir():
        raise InputError(f"--calibration {folder}: no such folder")
    if (folder / "evaluation.json").is_file():
        return "evaluate"
    if (folder / "metrics.json").is_file():
        return "run"
    raise InputError(f"--calibration {folder}: no metrics.json ('calibrate run') or "
                     "evaluation.json ('calibrate evaluate') in it")  # fmt: skip


#: At most this many real rows are listed (with their replay links) on the page.
MAX_LISTED_ROWS = 2000


def _run_view(folder: Path) -> dict[str, object]:
    metrics = _read_json(folder / "metrics.json")
    try:
        runs = [{k: int(r[k]) for k in ("tp", "fp", "fn", "tn")} for r in metrics["runs"]]
        mean = {k: metrics["mean"][k] for k in ("f05", "precision", "recall", "accuracy")}
    except (KeyError, TypeError, ValueError) as exc:
        raise InputError(f"{folder.name}/metrics.json: not written by 'calibrate run' "
                         f"({type(exc).__name__}: {exc})") from None  # fmt: skip
    pooled = {k: sum(r[k] for r in runs) for k in ("tp", "fp", "fn", "tn")}
    out: dict[str, object] = {
        "kind": "run", "profile": metrics.get("profile"), "n_real": metrics.get("n_real"),
        "runs": len(runs), "confusion": pooled,
        "confusion_label": f"every real row × {len(runs)} virtual run(s), pooled",
        "metrics": mean, "f05": {"value": mean["f05"], "low": None, "high": None,
                                  "method": None}, "shares": [], "notes": [],
    }  # fmt: skip
    preds = folder / "predictions.csv"
    if not preds.is_file():
        out["notes"].append("no predictions.csv (written by 'calibrate run' since this "
                            "version): no interval and no per-core shares")  # fmt: skip
        return out
    with preds.open(newline="", encoding="utf-8") as fh:
        rows = list(csv.DictReader(fh))
    cols = sorted((c for c in (rows[0] if rows else {}) if c.startswith("pred_run")),
                  key=lambda c: int(c[8:]) if c[8:].isdigit() else -1)  # fmt: skip
    try:
        actual = np.array([int(r["success"]) for r in rows])
        predicted = np.array([[int(r[c]) for r in rows] for c in cols])
        objects = np.array([str(r["object_id"]) for r in rows])
    except (KeyError, ValueError) as exc:
        raise InputError(f"{folder.name}/predictions.csv: bad row ({exc})") from None
    if not rows or len(cols) != len(runs) or set(np.unique(predicted)) - {0, 1}:
        raise InputError(f"{folder.name}/predictions.csv does not match metrics.json")
    low, high = bootstrap_f05(predicted, actual)
    out["f05"] = {"value": mean["f05"], "low": low, "high": high,
                  "method": f"percentile bootstrap over the {len(rows)} real rows "
                            f"({BOOTSTRAP_REPLICATES} resamples)"}  # fmt: skip
    per_core = {}
    for o in np.unique(objects):
        m = objects == o
        per_core[str(o)] = (int(actual[m].sum()), int(m.sum()), int(predicted[:, m].sum()),
                            int(m.sum()) * len(cols))  # fmt: skip
    out["shares"] = _shares(per_core)
    # The real rows with each run's prediction: the page links each row × run to its replay.
    out["rows"] = [
        {"row": int(r["row"]) if str(r.get("row", "")).isdigit() else i,
         "object_id": r["object_id"], "face": r.get("face"), "conveyor": r.get("conveyor"),
         "theta_deg": r.get("theta_deg"), "success": int(actual[i]),
         "predicted": [int(v) for v in predicted[:, i]]}
        for i, r in enumerate(rows[:MAX_LISTED_ROWS])
    ]  # fmt: skip
    out["rows_total"] = len(rows)
    return out


def _evaluate_view(folder: Path) -> dict[str, object]:
    ev = _read_json(folder / "evaluation.json")
    try:
        per_object = ev["per_object"]
        runs = int(ev["runs"]) if ev.get("runs") is not None else 1
        cv = {o: {k: int(d["cv"][k]) for k in ("tp", "fp", "fn", "tn")}
              for o, d in per_object.items()}  # fmt: skip
        counts = {o: (int(d["real_successes"]), int(d["n"]), float(d["twin_mean_p"]))
                  for o, d in per_object.items()}  # fmt: skip
        twin_cv = ev["twin_cv"]
    except (KeyError, TypeError, ValueError, AttributeError) as exc:
        raise InputError(f"{folder.name}/evaluation.json: not written by 'calibrate evaluate' "
                         f"({type(exc).__name__}: {exc})") from None  # fmt: skip
    pooled = {k: sum(c[k] for c in cv.values()) for k in ("tp", "fp", "fn", "tn")}
    if sum(pooled.values()) == 0:
        raise InputError(f"{folder.name}/evaluation.json: no real rows")
    pred, act = _vector_of(pooled)
    low, high = bootstrap_f05(pred, act)
    value = float(f05_of_counts(pooled["tp"], pooled["fp"], pooled["fn"]))
    tp, fp, fn, tn = (pooled[k] for k in ("tp", "fp", "fn", "tn"))
    per_core = {o: (k, n, round(p * n * runs), n * runs) for o, (k, n, p) in counts.items()}
    figures = {name: {"f05": ev[name].get("f05"), "f05_std": ev[name].get("f05_std")}
               for name in ("base_rate", "logistic_cv", "twin_in_sample", "twin_cv")
               if isinstance(ev.get(name), dict)}  # fmt: skip
    return {
        "kind": "evaluate", "profile": ev.get("profile"), "n_real": ev.get("n_real"),
        "runs": ev.get("runs"), "confusion": pooled,
        "confusion_label": "the twin held out (first repeat of the stratified K-fold CV)",
        "metrics": {"f05": value, "precision": tp / (tp + fp) if tp + fp else 0.0,
                    "recall": tp / (tp + fn) if tp + fn else 0.0,
                    "accuracy": (tp + tn) / (tp + fp + fn + tn)},
        "f05": {"value": value, "low": low, "high": high,
                "method": f"percentile bootstrap over the {tp + fp + fn + tn} real rows "
                          f"({BOOTSTRAP_REPLICATES} resamples)",
                "cv_mean": twin_cv.get("f05"), "cv_std": twin_cv.get("f05_std")},
        "figures": figures, "shares": _shares(per_core),
        "notes": ["simulated share: the twin's P(success) per real row × runs, rounded "
                  "(as 'calibrate evaluate' draws it in fidelity.png)"],
    }  # fmt: skip


def calibration_view(folder: Path) -> dict[str, object]:
    """Everything the calibration page draws for one output folder (JSON-ready)."""
    kind = check_calibration_dir(folder)
    out = _run_view(folder) if kind == "run" else _evaluate_view(folder)
    out["name"] = folder.name
    return _clean(out)


def _clean(value: object) -> object:
    """JSON has no NaN or infinity: such floats become None (recursively)."""
    if isinstance(value, float):
        return value if math.isfinite(value) else None
    if isinstance(value, Mapping):
        return {k: _clean(v) for k, v in value.items()}
    if isinstance(value, Sequence) and not isinstance(value, str):
        return [_clean(v) for v in value]
    return value
