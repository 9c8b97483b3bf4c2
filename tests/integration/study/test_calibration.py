"""A small virtual calibration against real rows (Sec. 6.5, Appendix A.2)."""

from __future__ import annotations

import csv
import json

import pytest

from transfertwin import InputError
from transfertwin.cli import main
from transfertwin.sim import SceneConfig
from transfertwin.study.calibration._replay import calibrate, parse_object_map


def _real_rows(n: int) -> list[dict]:
    from importlib import resources

    src = resources.files("transfertwin.data").joinpath("calibration_experiments.csv")
    with src.open() as fh:
        rows = list(csv.DictReader(fh))[:n]
    for r in rows:
        r["theta_deg"], r["success"] = int(r["theta_deg"]), int(r["success"])
    return rows


def test_calibration_scores_each_run_against_the_real_outcomes():
    rows = _real_rows(4)
    result = calibrate(rows, runs=2, scene=SceneConfig(), workers=1)
    assert result.actual == tuple(r["success"] for r in rows)
    assert len(result.runs) == 2
    for run in result.runs:
        tp = sum(p == 1 and a == 1 for p, a in zip(run.predicted, result.actual, strict=True))
        fp = sum(p == 1 and a == 0 for p, a in zip(run.predicted, result.actual, strict=True))
        assert (run.confusion.tp, run.confusion.fp) == (tp, fp)
        assert run.confusion.total == 4
    summary = result.summary()["metrics"]["f05"]
    assert summary["mean"] == pytest.approx(sum(summary["values"]) / 2)


def test_object_map_defaults_to_builtin_ids_and_rejects_unknowns(tmp_path):
    assert parse_object_map(None, ["o1", "o18"]) == {"o1": "o1", "o18": "o18"}
    assert parse_object_map("o1=o5", ["o1"]) == {"o1": "o5"}
    with pytest.raises(InputError, match="o99"):
        parse_object_map(None, ["o99"])
    with pytest.raises(InputError, match="ID=PATH"):
        parse_object_map("o1", ["o1"])


def test_calibrate_run_cli_writes_metrics_json(tmp_path, capsys):
    out = tmp_path / "cal"
    rc = main(["calibrate", "run", "--runs", "2", "--limit", "3", "--workers", "1",
               "--out", str(out)])  # fmt: skip
    assert rc == 0
    data = json.loads((out / "metrics.json").read_text())
    assert len(data["runs"]) == 2
    for key in ("tp", "fp", "fn", "tn", "precision", "recall", "accuracy", "f05"):
        assert key in data["runs"][0]
    assert {"f05", "precision", "recall", "accuracy"} <= data["mean"].keys()
    assert data["object_map"] == {"o1": "o1"}
    assert "not public" in capsys.readouterr().out
    with (out / "predictions.csv").open() as f:
        preds = list(csv.DictReader(f))
    real = _real_rows(3)
    assert [int(p["success"]) for p in preds] == [int(r["success"]) for r in real]
    for r in (0, 1):  # each run's predictions reproduce its confusion matrix
        tp = sum(p[f"pred_run{r}"] == "1" and p["success"] == "1" for p in preds)
        fp = sum(p[f"pred_run{r}"] == "1" and p["success"] == "0" for p in preds)
        assert (tp, fp) == (data["runs"][r]["tp"], data["runs"][r]["fp"])


def test_calibrate_run_with_one_run_prints_no_nan_spread(tmp_path, capsys):
    out = tmp_path / "cal1"
    assert main(["calibrate", "run", "--runs", "1", "--limit", "2", "--workers", "1",
                 "--out", str(out)]) == 0  # fmt: skip
    printed = capsys.readouterr().out
    assert "nan" not in printed and "one run: no spread" in printed
    assert "NaN" not in (out / "metrics.json").read_text()  # strict JSON: null


def test_calibrate_tune_saves_a_loadable_profile(tmp_path):
    from transfertwin.study import load_profile

    out = tmp_path / "tune"
    rc = main(["calibrate", "tune", "--method", "tpe", "--trials", "2", "--runs", "1",
               "--limit", "2", "--workers", "1", "--out", str(out)])  # fmt: skip
    assert rc == 0
    name, scene = load_profile(out / "profile.toml")
    assert name == "calibrated"
    assert 0.2 <= scene.mu <= 0.8 and 0.005 <= scene.gap_m <= 0.04
    assert (out / "trials.csv").read_text().count("\n") == 3
    assert (out / "scores.png").stat().st_size > 1000


def test_calibrate_sweep_bad_metric_is_exit_2(tmp_path, capsys):
    rc = main(["calibrate", "sweep", "--param", "mu", "--values", "0.3", "--metric", "auc",
               "--limit", "1", "--out", str(tmp_path / "s")])  # fmt: skip
    assert rc == 2
    assert "auc" in capsys.readouterr().err


def test_simulation_parameter_study_records_the_chosen_set(tmp_path):
    out = tmp_path / "sim"
    rc = main(["calibrate", "simstudy", "--sets", "S0,S5", "--runs", "1", "--limit", "2",
               "--workers", "1", "--out", str(out)])  # fmt: skip
    assert rc == 0
    chosen = json.loads((out / "chosen.json").read_text())
    assert chosen["label"] in {"S0", "S5"}
    assert (out / "profile.toml").exists()
    assert (out / "trials.csv").read_text().count("\n") == 3


def test_simulation_parameter_study_rejects_unknown_sets(tmp_path, capsys):
    assert main(["calibrate", "simstudy", "--sets", "S99", "--out", str(tmp_path / "x")]) == 2
    assert "S99" in capsys.readouterr().err
