"""ChArUco docking-error measurement (Sec. 6.1.2, Eq. 6.11): recovery on noise-free renders."""

from __future__ import annotations

import math

import numpy as np
import pytest

from transfertwin.navigation import CharucoRig


@pytest.fixture(scope="module")
def rig() -> CharucoRig:
    return CharucoRig()


def test_eq_6_11_on_true_transforms_returns_the_planar_error(rig) -> None:
    xi = np.array([-0.0082, 0.0053, math.radians(1.6)])
    ref, cur = rig.true_board_pose(np.zeros(3)), rig.true_board_pose(xi)
    assert np.allclose(rig.error_from(ref, cur), xi, atol=1e-12)


@pytest.mark.parametrize(
    "xi_mm_deg",
    [(0.0, 0.0, 0.0), (-8.18, 5.29, 1.60), (-2.91, -13.28, 1.13), (25.0, -25.0, -4.0)],
)
def test_eq_6_11_recovers_the_docking_error_within_1mm_and_0_2deg(rig, xi_mm_deg) -> None:
    x, y, t = xi_mm_deg
    xi = np.array([x / 1000, y / 1000, math.radians(t)])
    measured = rig.measure_error(xi)
    assert measured is not None
    assert abs(measured[0] - xi[0]) < 1e-3 and abs(measured[1] - xi[1]) < 1e-3
    assert abs(math.degrees(measured[2] - xi[2])) < 0.2


def test_board_out_of_view_is_not_measured(rig) -> None:
    assert rig.measure_error(np.array([0.19, 0.19, 0.0])) is None
