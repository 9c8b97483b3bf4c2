"""`rehearse` on the mismatch plant end to end (issue 29): a tiny configuration runs, says
which plant it ran on and scores one decision per held-out row."""

from __future__ import annotations

import json
import math

import pytest

from transfertwin.rehearsal import RehearsalConfig, rehearse


@pytest.mark.slow
def test_a_tiny_rehearsal_on_the_mismatch_plant(tmp_path) -> None:
    cfg = RehearsalConfig(plant_seed=2, objects=("o3",), calibration_experiments=4, runs=1,
                          validation_runs=1, theta_step=180, depths_mm=(16.0,),
                          plant_kind="mismatch")  # fmt: skip
    doc = rehearse(cfg, tmp_path)
    on_disk = json.loads((tmp_path / "rehearsal.json").read_text())
    assert on_disk["config"]["plant_kind"] == "mismatch"
    t = doc["thresholded"]
    assert t["threshold_before"] == t["threshold_after"] == 0.5  # R = 1: any t, no replay
    assert t["threshold_source"].startswith("0.5 (R = 1") and 0.0 <= t["f05_after"] <= 1.0
    assert 0.0 <= t["brier_after"] <= 1.0
    assert doc["held_out"] == 1 and math.isnan(t["f05_after_ci"][0])  # one row: no interval


@pytest.mark.slow
def test_with_two_runs_a_row_the_thresholds_are_chosen_on_the_training_rows(tmp_path) -> None:
    cfg = RehearsalConfig(plant_seed=2, objects=("o3",), calibration_experiments=6, runs=2,
                          validation_runs=1, theta_step=180, depths_mm=(16.0,))  # fmt: skip
    doc = rehearse(cfg, tmp_path)
    t = doc["thresholded"]
    n = doc["training"]
    assert t["threshold_source"] == f"chosen on the {n} training rows (best F0.5 there)"
    assert {t["threshold_before"], t["threshold_after"]} <= {0.5, 1.0, 1e-6}  # P of 2 runs
    # the training rows were replayed twice (before, after), R runs each
    replays = 2 * doc["training"] * cfg.runs
    assert doc["virtual_experiments"] >= replays + doc["held_out"] * cfg.runs * 2
