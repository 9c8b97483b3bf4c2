"""Visual servoing (Sec. 5.4.4): the closed form of Eq. 5.14 against independent checks."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.optimize import brentq

from transfertwin._errors import InputError
from transfertwin.perception import (
    ServoRig,
    camera_pose,
    eq_5_14,
    servo_angle,
    servo_chain_2d,
)

RIG = ServoRig()
POINTS = [(-0.6, 0.0), (-0.325, 0.06), (-0.2, 0.1), (0.0, 0.0), (0.3, 0.05), (0.45, 0.12)]


@pytest.mark.parametrize(("x", "z"), POINTS)
def test_eq_5_13_holds_at_the_closed_form_solution(x, z) -> None:
    alpha, d_z = servo_angle(RIG, x, z)
    np.testing.assert_allclose(eq_5_14(RIG, alpha, d_z, (x, z)), [0.0, 0.0, 1.0], atol=1e-12)


@pytest.mark.parametrize(("x", "z"), POINTS)
def test_eq_5_12_angle_matches_a_root_found_numerically(x, z) -> None:
    """Eq. 5.12 asks for a zero x_C component of the object in F_C; bracket that root in
    the servo's range with the 3-D camera pose (another code path than the closed form)."""

    def x_in_camera(alpha: float) -> float:
        pose = camera_pose(RIG, alpha)
        return float((np.linalg.inv(pose) @ np.array([x, 0.0, z, 1.0]))[0])

    root = brentq(x_in_camera, -math.radians(80), math.radians(80), xtol=1e-14)
    assert servo_angle(RIG, x, z)[0] == pytest.approx(root, abs=1e-10)


def test_without_camera_offset_the_angle_is_the_bearing_from_the_axis() -> None:
    rig = ServoRig(camera_offset_m=(0.0, 0.05))
    x_s, _, z_s = rig.servo_xyz_m
    for x, z in POINTS:
        expected = math.atan2(x - x_s, z_s - z)  # tilt towards +x from straight down
        assert servo_angle(rig, x, z)[0] == pytest.approx(expected, abs=1e-12)


def test_fig_5_15b_alpha_zero_does_not_depend_on_z() -> None:
    x0 = RIG.servo_xyz_m[0] + RIG.camera_offset_m[0]
    for z in (0.0, 0.05, 0.1, 0.2, 0.3):
        assert servo_angle(RIG, x0, z)[0] == pytest.approx(0.0, abs=1e-12)
    # Away from α = 0 the angle does depend on z (the contour lines fan out).
    a_low, a_high = servo_angle(RIG, 0.3, 0.0)[0], servo_angle(RIG, 0.3, 0.2)[0]
    assert a_high > a_low + math.radians(5)


def test_angle_grows_towards_the_tu() -> None:
    alphas = [servo_angle(RIG, x, 0.05)[0] for x in np.linspace(-0.6, 0.5, 12)]
    assert np.all(np.diff(alphas) > 0)


def test_2d_chain_is_the_3d_camera_pose_in_the_xz_plane() -> None:
    for alpha in (-0.7, 0.0, 0.4):
        pose, chain = camera_pose(RIG, alpha), servo_chain_2d(RIG, alpha)
        np.testing.assert_allclose(chain[:2, 2], pose[[0, 2], 3], atol=1e-12)
        np.testing.assert_allclose(chain[:2, 1], pose[[0, 2], 2], atol=1e-12)  # optical axis


def test_point_at_the_axis_is_refused() -> None:
    x_s, _, z_s = RIG.servo_xyz_m
    with pytest.raises(InputError, match=r"Eq\. 5\.14"):
        servo_angle(RIG, x_s, z_s)
