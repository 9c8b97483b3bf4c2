"""The console's calibration page data, from folders written the way `calibrate run` and
`calibrate evaluate` write them; expected numbers come from scipy/sklearn and plain loops,
not from the code under test."""

from __future__ import annotations

import csv
import json

import numpy as np
import pytest
from scipy.stats import beta
from sklearn.metrics import fbeta_score

from transfertwin._errors import InputError
from transfertwin.web import (
    bootstrap_f05,
    calibration_view,
    check_calibration_dir,
    f05_of_counts,
)

# real outcome, o-id, and two runs' virtual outcomes per real row
ROWS = [
    ("o1", 1, 1, 1), ("o1", 0, 0, 1), ("o1", 1, 0, 1), ("o1", 0, 0, 0), ("o1", 1, 1, 1),
    ("o2", 0, 1, 0), ("o2", 0, 0, 0), ("o2", 1, 1, 1), ("o10", 1, 1, 0), ("o10", 0, 0, 0),
]  # fmt: skip


def _cp(k: int, n: int) -> tuple[float, float]:
    low = 0.0 if k == 0 else beta.ppf(0.025, k, n - k + 1)
    high = 1.0 if k == n else beta.ppf(0.975, k + 1, n - k)
    return low, high


def _confusion(pred, act) -> dict[str, int]:
    return {"tp": sum(p and a for p, a in zip(pred, act, strict=True)),
            "fp": sum(p and not a for p, a in zip(pred, act, strict=True)),
            "fn": sum(a and not p for p, a in zip(pred, act, strict=True)),
            "tn": sum(not a and not p for p, a in zip(pred, act, strict=True))}  # fmt: skip


@pytest.fixture
def run_dir(tmp_path):
    out = tmp_path / "cal-run"
    out.mkdir()
    act = [r[1] for r in ROWS]
    runs = []
    for r in (0, 1):
        pred = [row[2 + r] for row in ROWS]
        runs.append({"run": r, **_confusion(pred, act),
                     "f05": fbeta_score(act, pred, beta=0.5, zero_division=0)})  # fmt: skip
    mean = {k: float(np.mean([r[k] for r in runs])) for k in ("tp", "fp", "fn", "tn", "f05")}
    mean |= {"precision": 0.5, "recall": 0.5, "accuracy": 0.5}  # not recomputed by the view
    (out / "metrics.json").write_text(json.dumps({"profile": "default", "n_real": len(ROWS),
                                                  "runs": runs, "mean": mean}))  # fmt: skip
    with (out / "predictions.csv").open("w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(["row", "object_id", "face", "conveyor", "theta_deg", "success",
                    "pred_run0", "pred_run1"])  # fmt: skip
        for i, (o, y, p0, p1) in enumerate(ROWS):
            w.writerow([i, o, "front", "both", 0, y, p0, p1])
    return out


def test_f05_of_counts_matches_sklearn():
    rng = np.random.default_rng(1)
    for _ in range(20):
        act, pred = rng.integers(0, 2, 30), rng.integers(0, 2, 30)
        c = _confusion(pred, act)
        expected = fbeta_score(act, pred, beta=0.5, zero_division=0)
        assert f05_of_counts(c["tp"], c["fp"], c["fn"]) == pytest.approx(expected)
    assert f05_of_counts(0, 0, 0) == 0.0


def test_bootstrap_matches_a_plain_loop():
    act = np.array([r[1] for r in ROWS])
    pred = np.array([[r[2] for r in ROWS], [r[3] for r in ROWS]])
    low, high = bootstrap_f05(pred, act, replicates=300, seed=7)
    rng = np.random.default_rng(7)
    idx = rng.integers(0, len(act), size=(300, len(act)))
    stats = [np.mean([fbeta_score(act[i], p[i], beta=0.5, zero_division=0) for p in pred])
             for i in idx]  # fmt: skip
    assert (low, high) == pytest.approx(tuple(np.quantile(stats, [0.025, 0.975])))
    assert bootstrap_f05(pred, act, replicates=300, seed=7) == (low, high)  # same seed, same bits
    with pytest.raises(InputError):
        bootstrap_f05(pred[:, :3], act)


def test_run_folder_view(run_dir):
    v = calibration_view(run_dir)
    assert v["kind"] == "run" and v["runs"] == 2 and v["name"] == "cal-run"
    act = [r[1] for r in ROWS]
    pooled = [_confusion([row[2 + r] for row in ROWS], act) for r in (0, 1)]
    assert v["confusion"] == {k: pooled[0][k] + pooled[1][k] for k in pooled[0]}
    f = v["f05"]
    assert f["low"] <= f["value"] <= f["high"] and "bootstrap" in f["method"]
    assert [s["object_id"] for s in v["shares"]] == ["o1", "o2", "o10"]  # natural order
    for s in v["shares"]:
        mine = [r for r in ROWS if r[0] == s["object_id"]]
        k_real, k_sim = sum(r[1] for r in mine), sum(r[2] + r[3] for r in mine)
        assert (s["real"]["k"], s["real"]["n"]) == (k_real, len(mine))
        assert (s["sim"]["k"], s["sim"]["n"]) == (k_sim, 2 * len(mine))
        assert (s["real"]["low"], s["real"]["high"]) == pytest.approx(_cp(k_real, len(mine)))
        assert (s["sim"]["low"], s["sim"]["high"]) == pytest.approx(_cp(k_sim, 2 * len(mine)))


def test_run_folder_without_predictions_has_no_interval(run_dir):
    (run_dir / "predictions.csv").unlink()
    v = calibration_view(run_dir)
    assert v["f05"]["low"] is None and v["shares"] == [] and v["notes"]


def test_evaluate_folder_view(tmp_path):
    out = tmp_path / "cal-eval"
    out.mkdir()
    per_object = {
        "o1": {"n": 8, "real_successes": 3, "twin_mean_p": 0.5,
               "in_sample": {"tp": 3, "fp": 1, "fn": 0, "tn": 4},
               "cv": {"tp": 2, "fp": 1, "fn": 1, "tn": 4}},
        "o3": {"n": 4, "real_successes": 4, "twin_mean_p": 0.75,
               "in_sample": {"tp": 3, "fp": 0, "fn": 1, "tn": 0},
               "cv": {"tp": 3, "fp": 0, "fn": 1, "tn": 0}},
    }  # fmt: skip
    (out / "evaluation.json").write_text(json.dumps({
        "profile": "default", "n_real": 12, "runs": 2, "per_object": per_object,
        "twin_cv": {"f05": 0.7, "f05_std": 0.05}, "base_rate": {"f05": 0.6}}))  # fmt: skip
    v = calibration_view(out)
    assert v["kind"] == "evaluate"
    assert v["confusion"] == {"tp": 5, "fp": 1, "fn": 2, "tn": 4}
    assert v["f05"]["value"] == pytest.approx(1.25 * 5 / (1.25 * 5 + 0.25 * 2 + 1))
    assert v["f05"]["cv_mean"] == 0.7 and v["figures"]["base_rate"]["f05"] == 0.6
    o3 = next(s for s in v["shares"] if s["object_id"] == "o3")
    assert (o3["sim"]["k"], o3["sim"]["n"]) == (6, 8)  # 0.75 x 4 rows x 2 runs
    assert (o3["real"]["low"], o3["real"]["high"]) == pytest.approx(_cp(4, 4))


@pytest.mark.parametrize(
    ("files", "message"),
    [
        ({}, "no metrics.json"),
        ({"metrics.json": "{not json"}, "not JSON"),
        ({"metrics.json": "[1]"}, "not a JSON object"),
        ({"metrics.json": '{"runs": 3}'}, "not written by 'calibrate run'"),
        ({"evaluation.json": '{"per_object": {"o1": {}}}'}, "not written by 'calibrate eval"),
    ],
)  # fmt: skip
def test_bad_folders_are_input_errors(tmp_path, files, message):
    for name, text in files.items():
        (tmp_path / name).write_text(text)
    with pytest.raises(InputError, match=message):
        calibration_view(tmp_path)


def test_missing_folder_is_an_input_error(tmp_path):
    with pytest.raises(InputError, match="no such folder"):
        check_calibration_dir(tmp_path / "nowhere")
