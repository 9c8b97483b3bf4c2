"""Gap area between the docked belts (Sec. 5.5, Fig. 5.18) against the study's own
measurement of the same geometry (`gap_area_cm2` of the real calibration data)."""

from __future__ import annotations

import numpy as np
import pytest

from transfertwin.data import calibration_csv_path
from transfertwin.sim import DockingError, GapAreaLayout, LayoutConfig, gap_areas_cm2, gap_width_m
from transfertwin.store import DOCKING_ERROR_COLUMNS, read_results


def _areas(geo: GapAreaLayout) -> tuple[np.ndarray, np.ndarray]:
    rows = read_results(calibration_csv_path())
    errors = np.array([[float(r[c]) for c in DOCKING_ERROR_COLUMNS] for r in rows])
    sim = gap_areas_cm2(geo, errors, [str(r["conveyor"]) for r in rows])
    return sim, np.array([float(r["gap_area_cm2"]) for r in rows])


def _r2(pred: np.ndarray, real: np.ndarray) -> float:
    return 1.0 - np.sum((real - pred) ** 2) / np.sum((real - real.mean()) ** 2)


def test_fig_5_18_fitted_geometry_reproduces_the_measured_gap_area() -> None:
    sim, real = _areas(GapAreaLayout.fitted())
    assert _r2(sim, real) > 0.99
    assert abs(np.mean(sim - real)) < 0.2  # cm², bias


def test_fig_5_18_the_scene_belt_geometry_explains_most_but_not_all() -> None:
    sim, real = _areas(GapAreaLayout.from_layout(LayoutConfig()))
    assert 0.6 < _r2(sim, real) < 0.95  # 195 mm belts vs the ~245 mm strip the data imply


def test_eq_6_11_negative_x_error_widens_the_gap_and_yaw_tilts_it() -> None:
    geo = GapAreaLayout(gap_m=0.01)
    y = np.array([-0.1, 0.0, 0.1])
    assert gap_width_m(geo, DockingError.from_mm_deg(0, 0, 0), y) == pytest.approx([0.01] * 3)
    wider = gap_width_m(geo, DockingError.from_mm_deg(-5, 0, 0), y)
    assert wider == pytest.approx([0.015] * 3)
    turned = gap_width_m(geo, DockingError.from_mm_deg(0, 0, 2), y)
    assert turned[2] > turned[1] > turned[0]  # positive yaw opens the left side
