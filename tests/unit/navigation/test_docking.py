"""One docking run end to end, and the comparison with the real per-station errors."""

from __future__ import annotations

import math

import numpy as np
import pytest

from transfertwin.data import calibration_csv_path
from transfertwin.navigation import compare_with_real, default_floor, simulate_docking


def test_docking_is_a_pure_function_of_the_seed_and_lands_near_the_goal() -> None:
    floor = default_floor()
    a = simulate_docking(floor, "B", seed=4, run=0)
    b = simulate_docking(floor, "B", seed=4, run=0)
    c = simulate_docking(floor, "B", seed=5, run=0)
    assert a.status == "ok"
    assert a.error.tobytes() == b.error.tobytes()
    assert not np.array_equal(a.error, c.error)
    assert abs(a.error[0]) < 0.05 and abs(a.error[1]) < 0.05
    assert abs(a.error[2]) < math.radians(5)
    goal = floor.station("B").goal_pose()
    assert np.linalg.norm(a.trace[-1, :2] - goal[:2]) < 0.06


def test_comparison_of_the_real_rows_with_themselves() -> None:
    import csv

    rows = list(csv.DictReader(calibration_csv_path().open()))
    a_rows = [r for r in rows if r["transfer_unit"] == "TU_A"]
    sim = np.array([[float(r[c]) for c in ("dock_err_x_mm", "dock_err_y_mm",
                    "dock_err_theta_deg")] for r in a_rows])  # fmt: skip
    out = compare_with_real(sim, ["TU_A"] * len(sim))
    assert [c.column for c in out] == ["dock_err_x_mm", "dock_err_y_mm", "dock_err_theta_deg"]
    x = out[0]
    assert x.n_sim == x.n_real == len(a_rows) == 58
    assert x.mean_real == pytest.approx(-8.18, abs=0.01)  # Fig. 6.9 data, TU_A
    assert x.ks_statistic == 0.0 and x.ks_pvalue == 1.0
    shifted = compare_with_real(sim + np.array([30.0, 0, 0]), ["TU_A"] * len(sim))[0]
    assert shifted.ks_statistic == 1.0 and shifted.ks_pvalue < 1e-10
