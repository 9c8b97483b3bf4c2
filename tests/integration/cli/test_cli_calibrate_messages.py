"""What `calibrate run` says about undefined metrics and about scans (issue 30, item 8).

Hand-derived: a table with only real failures has TP + FN = 0, so recall (Eq. A.2) and
F0.5 (Eq. A.4) are undefined whatever the twin predicts; a twin that also predicts only
failures has TP + FP = 0, so precision (Eq. A.1) is undefined too.
"""

from __future__ import annotations

import csv
import json
from pathlib import Path

from transfertwin.cli._calibrate_out import builtin_real, mapping_line, metric_line
from transfertwin.data import calibration_csv_path
from transfertwin.store import read_results
from transfertwin.study.calibration import ConfusionMatrix, summarize_runs

PLANT_HEADER = ("experiment_id,transfer_unit,object_id,theta_deg,face,conveyor,success,"
                "dock_err_x_mm,dock_err_y_mm,dock_err_theta_deg,gap_area_cm2")  # fmt: skip


def lines(*runs: ConfusionMatrix) -> dict[str, str]:
    summary = summarize_runs(runs)["metrics"]
    return {k: metric_line(k, summary, runs) for k in ("f05", "precision", "recall")}


def test_only_real_failures_and_only_predicted_failures_give_n_a_with_the_reason() -> None:
    out = lines(ConfusionMatrix(tp=0, fp=0, fn=0, tn=12), ConfusionMatrix(0, 0, 0, 12))
    assert out["f05"] == ("f05       n/a (no predicted successes and no real successes: "
                          "precision and recall undefined)")  # fmt: skip
    assert out["precision"] == "precision n/a (no predicted successes: precision undefined)"
    assert out["recall"] == "recall    n/a (no real successes: recall undefined)"


def test_only_real_failures_with_false_alarms_leave_f05_undefined() -> None:
    out = lines(ConfusionMatrix(tp=0, fp=3, fn=0, tn=9))
    assert out["f05"] == "f05       n/a (no real successes: recall undefined)"
    assert out["precision"] == "precision 0.000 (one run: no spread)"


def test_a_run_without_predicted_successes_among_others_is_named() -> None:
    out = lines(ConfusionMatrix(4, 1, 2, 5), ConfusionMatrix(0, 0, 6, 6))
    assert out["precision"].startswith("precision 0.400 ± ")
    assert out["precision"].endswith(
        "(1 of 2 runs n/a, counted as 0: no predicted successes: precision undefined)"
    )


def test_defined_metrics_print_as_before() -> None:
    out = lines(ConfusionMatrix(4, 1, 2, 5))
    assert (
        out["f05"] == f"f05       {1.25 * 4 / (1.25 * 4 + 0.25 * 2 + 1):.3f} (one run: no spread)"
    )


def test_the_scans_remark_is_only_for_the_builtin_real_cores(tmp_path: Path) -> None:
    shipped = read_results(calibration_csv_path())
    assert builtin_real(shipped) and builtin_real(shipped[:5])
    assert "scans are not public" in mapping_line({"o1": "o1"}, True)
    plant = tmp_path / "plant_experiments.csv"
    plant.write_text(PLANT_HEADER + "\n0,TU_A,o3,-32,front,both,0,-10.38,9.48,1.98,25.78\n")
    assert not builtin_real(read_results(plant))
    line = mapping_line({"o3": "o3"}, False)
    assert line == "objects replayed with the meshes: o3->o3" and "scan" not in line


def test_calibrate_run_on_an_emulated_plant_with_only_failures(tmp_path: Path, capsys) -> None:
    from transfertwin.cli import main

    plant = tmp_path / "plant_experiments.csv"
    plant.write_text(PLANT_HEADER + "\n0,TU_A,o3,-32,front,both,0,-10.38,9.48,1.98,25.78\n")
    out = tmp_path / "cal"
    assert main(["calibrate", "run", "--real", str(plant), "--runs", "1", "--workers", "1",
                 "--out", str(out)]) == 0  # fmt: skip
    text = capsys.readouterr().out
    assert "scans" not in text
    assert "f05       n/a (" in text and "no real successes" in text
    assert json.loads((out / "metrics.json").read_text())["undefined"]["f05"]
    with (out / "predictions.csv").open(newline="") as fh:
        assert [r["object_id"] for r in csv.DictReader(fh)] == ["o3"]
