"""Eq. 6.11: the TU pose seen from a docked TM, ξ⁻¹ on the left."""

from __future__ import annotations

import math

import pytest

from transfertwin import InputError
from transfertwin.sim import DockingError, tu_pose_in_tip_frame

GAP, TIP = 0.01188, 0.40


def test_eq_6_11_zero_error_is_nominal_gap():
    assert tu_pose_in_tip_frame(DockingError(), GAP, TIP) == pytest.approx((GAP, 0.0, 0.0))


def test_eq_6_11_negative_x_error_widens_gap():
    x, y, yaw = tu_pose_in_tip_frame(DockingError.from_mm_deg(-10, 0, 0), GAP, TIP)
    assert x == pytest.approx(GAP + 0.010)
    assert (y, yaw) == pytest.approx((0.0, 0.0))


def test_eq_6_11_y_error_shifts_tu_the_other_way():
    _, y, _ = tu_pose_in_tip_frame(DockingError.from_mm_deg(0, 5, 0), GAP, TIP)
    assert y == pytest.approx(-0.005)


def test_eq_6_11_yaw_error_rotates_about_tm_centre_not_tip():
    theta = math.radians(2.0)
    x, y, yaw = tu_pose_in_tip_frame(DockingError(0, 0, theta), GAP, TIP)
    arm = TIP + GAP  # TU origin seen from the TM centre
    assert yaw == pytest.approx(-theta)
    assert x == pytest.approx(arm * math.cos(theta) - TIP)
    assert y == pytest.approx(-arm * math.sin(theta))
    assert abs(y) > 0.01  # a 2° yaw moves the TU sideways by more than a centimetre


def test_docking_error_rejects_absurd_values():
    with pytest.raises(InputError, match="out of range"):
        DockingError.from_mm_deg(500, 0, 0)
    with pytest.raises(InputError, match="finite"):
        DockingError(float("nan"), 0, 0)
