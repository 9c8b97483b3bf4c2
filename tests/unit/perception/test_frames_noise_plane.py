"""Frames (Table 5.1), the noise model and the seeded RANSAC plane."""

from __future__ import annotations

import math

import numpy as np
import pytest

from transfertwin._errors import InputError
from transfertwin.perception import (
    CameraIntrinsics,
    DepthNoise,
    ServoRig,
    apply_depth_noise,
    camera_pose,
    depth_to_points,
    ransac_plane,
)


def test_camera_looks_straight_down_at_alpha_zero_and_towards_tu_for_positive_alpha() -> None:
    rig = ServoRig()
    pose = camera_pose(rig, 0.0)
    np.testing.assert_allclose(pose[:3, 2], [0, 0, -1], atol=1e-12)  # z_C: optical axis
    np.testing.assert_allclose(pose[:3, 0], [1, 0, 0], atol=1e-12)  # image right = +x_T
    np.testing.assert_allclose(np.linalg.det(pose[:3, :3]), 1.0)
    assert camera_pose(rig, math.radians(20))[0, 2] > 0  # optical axis turned to +x


def test_back_projection_of_a_flat_floor_is_flat() -> None:
    intr = CameraIntrinsics(40, 30, 60.0)
    pts = depth_to_points(np.full((30, 40), 0.5), intr)
    assert np.allclose(pts[:, 2], 0.5)
    half = 0.5 * np.tan(np.radians(30)) * (29 / 30)  # outermost pixel centre
    assert pts[:, 1].max() == pytest.approx(half)
    assert pts[0, 0] < 0 and pts[0, 1] < 0  # top-left pixel: image left and up


def test_noise_is_seeded_and_depth_proportional() -> None:
    depth = np.concatenate([np.full((50, 100), 0.5), np.full((50, 100), 2.0)])
    noise = DepthNoise(sigma_rel=0.01, dropout=0.1)
    a, b = apply_depth_noise(depth, noise, 3), apply_depth_noise(depth, noise, 3)
    assert np.array_equal(a, b, equal_nan=True)
    assert not np.array_equal(a, apply_depth_noise(depth, noise, 4), equal_nan=True)
    near, far = a[:50] - 0.5, a[50:] - 2.0
    assert np.nanstd(near) == pytest.approx(0.005, rel=0.1)
    assert np.nanstd(far) == pytest.approx(0.02, rel=0.1)
    assert np.isnan(a).mean() == pytest.approx(0.1, abs=0.02)


def test_out_of_range_pixels_return_nothing() -> None:
    out = apply_depth_noise(np.array([[0.1, 1.0, 5.0]]), DepthNoise.clean(), 0)
    assert np.isnan(out[0, 0]) and out[0, 1] == 1.0 and np.isnan(out[0, 2])


def test_bad_noise_is_refused() -> None:
    with pytest.raises(InputError):
        DepthNoise(dropout=1.0)


def test_ransac_finds_the_plane_under_clutter_reproducibly() -> None:
    rng = np.random.default_rng(0)
    plane = np.c_[rng.uniform(-0.6, 0, 3000), rng.uniform(-0.2, 0.2, 3000),
                  0.01 + rng.normal(0, 0.001, 3000)]  # fmt: skip
    clutter = rng.uniform((-0.4, -0.1, 0.02), (-0.2, 0.1, 0.12), (800, 3))
    pts = np.concatenate([plane, clutter])
    model, inliers = ransac_plane(pts, 0.004, 100, seed=1)
    assert model[2] > 0.999 and -model[3] / model[2] == pytest.approx(0.01, abs=5e-4)
    assert inliers[:3000].mean() > 0.99 and inliers[3000:].mean() < 0.05
    again = ransac_plane(pts, 0.004, 100, seed=1)
    assert np.array_equal(model, again[0]) and np.array_equal(inliers, again[1])
