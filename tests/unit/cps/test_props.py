"""PropS pose fusion (Sec. 5.2): expected values derived by hand, not by the solver."""

from __future__ import annotations

import math

import numpy as np
import pytest

from transfertwin import InputError
from transfertwin.cps.apps._props import (
    Pose2D,
    PoseGraph,
    PoseObservation,
    fuse_poses,
    wrap_angle,
)


def obs(subject: str, x: float, y: float, theta_deg: float, sxy: float, sth: float,
        relative_to: str | None = None, source: str = "test") -> PoseObservation:  # fmt: skip
    return PoseObservation(source, subject, x, y, math.radians(theta_deg), sxy, sth, relative_to)


def angle_gap(a: float, b: float) -> float:
    """Smallest absolute difference of two angles, computed with atan2 (rad)."""
    return abs(math.atan2(math.sin(a - b), math.cos(a - b)))


@pytest.mark.parametrize(
    ("angle", "expected"),
    [(math.pi, math.pi), (-math.pi, math.pi), (1.5 * math.pi, -0.5 * math.pi), (0.25, 0.25),
     (-7.0, -7.0 + 2 * math.pi)],
)  # fmt: skip
def test_wrap_angle_to_half_open_interval(angle: float, expected: float) -> None:
    assert wrap_angle(angle) == pytest.approx(expected, abs=1e-12)


def test_two_world_observations_fuse_to_inverse_variance_mean() -> None:
    s1, s2 = 0.1, 0.2
    x1, x2, y1, y2 = 1.00, 1.30, 2.00, 1.90
    t1, t2 = 0.2, 0.5  # rad, sigma_theta equal to sigma_xy here
    g = PoseGraph()
    g.add(PoseObservation("TU_C", "TM_1", x1, y1, t1, s1, s1))
    g.add(PoseObservation("TM_1", "TM_1", x2, y2, t2, s2, s2))
    w1, w2 = 1 / s1**2, 1 / s2**2
    pose = g.solve()["TM_1"]
    assert pose.x == pytest.approx((w1 * x1 + w2 * x2) / (w1 + w2), abs=1e-9)  # 1.06
    assert pose.y == pytest.approx((w1 * y1 + w2 * y2) / (w1 + w2), abs=1e-9)
    assert pose.theta == pytest.approx((w1 * t1 + w2 * t2) / (w1 + w2), abs=1e-9)
    cov = g.covariance("TM_1")
    np.testing.assert_allclose(np.diag(cov), [1 / (w1 + w2)] * 3, rtol=1e-9)  # 0.008
    np.testing.assert_allclose(cov - np.diag(np.diag(cov)), 0.0, atol=1e-12)
    # squared residual norm = sum of weighted squared deviations from the mean
    chi2 = sum(w1 * w2 / (w1 + w2) * d**2 for d in (x1 - x2, y1 - y2, t1 - t2))
    assert g.residual_norm == pytest.approx(math.sqrt(chi2), rel=1e-9)


def test_angles_wrap_around_pi() -> None:
    g = PoseGraph()
    g.add(obs("TM_1", 0.0, 0.0, 179.0, 0.1, 0.05))
    g.add(obs("TM_1", 0.0, 0.0, -179.0, 0.1, 0.05))
    theta = g.fused("TM_1").theta
    assert angle_gap(theta, math.pi) < 1e-9
    assert -math.pi < theta <= math.pi
    assert g.residual_norm == pytest.approx(math.sqrt(2) * math.radians(1.0) / 0.05, rel=1e-6)


def test_chain_with_world_prior_gives_the_composition() -> None:
    g = PoseGraph()
    g.add(obs("A", 1.0, 2.0, 30.0, 0.01, 0.01))
    g.add(obs("B", 2.0, 0.0, 90.0, 0.05, 0.02, relative_to="A"))
    g.add(obs("C", 1.0, 1.0, -45.0, 0.05, 0.02, relative_to="B"))
    # B = A ∘ (2, 0, 90°): A's heading 30°, so B = (1 + 2 cos30°, 2 + 2 sin30°, 120°)
    xb, yb = 1.0 + 2.0 * math.cos(math.radians(30)), 2.0 + 2.0 * math.sin(math.radians(30))
    # C = B ∘ (1, 1, -45°): rotate (1, 1) by 120°
    c, s = math.cos(math.radians(120)), math.sin(math.radians(120))
    xc, yc = xb + c * 1.0 - s * 1.0, yb + s * 1.0 + c * 1.0
    poses = g.solve()
    assert (poses["B"].x, poses["B"].y) == pytest.approx((xb, yb), abs=1e-9)
    assert angle_gap(poses["B"].theta, math.radians(120)) < 1e-9
    assert (poses["C"].x, poses["C"].y) == pytest.approx((xc, yc), abs=1e-9)
    assert angle_gap(poses["C"].theta, math.radians(75)) < 1e-9
    assert g.residual_norm == pytest.approx(0.0, abs=1e-9)


def test_inconsistent_loop_is_distributed_by_variance() -> None:
    # A anchored at the origin; A→B and B→C each 1 m along x, but A→C says 2.3 m.
    s1, s2, s3 = 0.01, 0.02, 0.03
    g = PoseGraph()
    g.add(obs("B", 1.0, 0.0, 0.0, s1, 0.01, relative_to="A"))
    g.add(obs("C", 1.0, 0.0, 0.0, s2, 0.01, relative_to="B"))
    g.add(obs("C", 2.3, 0.0, 0.0, s3, 0.01, relative_to="A"))
    poses = g.solve(anchor="A")
    # loop misclosure e = 0.3 m; edge i absorbs e * σi² / Σσ²
    e, total = 0.3, s1**2 + s2**2 + s3**2
    assert poses["A"] == Pose2D(0.0, 0.0, 0.0)
    assert poses["B"].x == pytest.approx(1.0 + e * s1**2 / total, abs=1e-9)
    assert poses["C"].x - poses["B"].x == pytest.approx(1.0 + e * s2**2 / total, abs=1e-9)
    assert poses["C"].x == pytest.approx(2.3 - e * s3**2 / total, abs=1e-9)
    assert g.residual_norm == pytest.approx(e / math.sqrt(total), rel=1e-9)


def test_docking_pose_from_camera_and_localisation() -> None:
    # TU_C's pose is known (world prior), its camera sees TM_1 0.5 m ahead; TM_1's own
    # localisation says x = 2.6. With all headings 0 the x estimates combine linearly:
    # camera path variance σ_tu² + σ_cam², localisation σ_loc².
    s_tu, s_cam, s_loc = 0.02, 0.03, 0.04
    g = PoseGraph()
    g.add(obs("TU_C", 2.0, 1.0, 0.0, s_tu, 1e-4, source="map"))
    g.add(obs("TM_1", 0.5, 0.0, 0.0, s_cam, 0.01, relative_to="TU_C", source="TU_C"))
    g.add(obs("TM_1", 2.6, 1.0, 0.0, s_loc, 0.01, source="TM_1"))
    w_cam, w_loc = 1 / (s_tu**2 + s_cam**2), 1 / s_loc**2
    expected = (w_cam * 2.5 + w_loc * 2.6) / (w_cam + w_loc)
    assert g.fused("TM_1").x == pytest.approx(expected, abs=1e-9)
    assert g.covariance("TM_1")[0, 0] == pytest.approx(1 / (w_cam + w_loc), rel=1e-9)


@pytest.mark.parametrize("heading_deg", [0.0, 90.0, 30.0])
def test_chain_covariance_follows_pose_compounding(heading_deg: float) -> None:
    sxy, sth = 0.1, 0.05
    g = PoseGraph()
    g.add(obs("B", 1.0, 0.0, heading_deg, sxy, sth, relative_to="A"))
    g.add(obs("C", 1.0, 0.5, 0.0, sxy, sth, relative_to="B"))
    g.solve(anchor="A")
    np.testing.assert_allclose(g.covariance("A"), np.zeros((3, 3)))
    sigma = np.diag([sxy**2, sxy**2, sth**2])
    np.testing.assert_allclose(g.covariance("B"), sigma, atol=1e-15)
    # First-order compounding C = B ⊕ z (Smith & Cheeseman): Σ_C = J_B Σ_B J_Bᵀ + J_z Σ_z J_zᵀ
    t = math.radians(heading_deg)
    c, s = math.cos(t), math.sin(t)
    zx, zy = 1.0, 0.5
    j_b = np.array([[1, 0, -s * zx - c * zy], [0, 1, c * zx - s * zy], [0, 0, 1]])
    j_z = np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]])
    expected = j_b @ sigma @ j_b.T + j_z @ sigma @ j_z.T
    np.testing.assert_allclose(g.covariance("C"), expected, rtol=1e-9, atol=1e-15)


def test_adding_an_observation_updates_the_fused_pose() -> None:
    g = PoseGraph()
    g.add(obs("TM_1", 1.0, 0.0, 0.0, 0.1, 0.1))
    assert g.fused("TM_1").x == pytest.approx(1.0)
    g.add(obs("TM_1", 2.0, 0.0, 0.0, 0.1, 0.1))
    assert g.fused("TM_1").x == pytest.approx(1.5)
    assert len(g.observations) == 2


def test_pose_inverse_composes_to_identity() -> None:
    p = Pose2D(1.2, -0.4, 2.5)
    q = p.compose(p.inverse())
    assert (q.x, q.y, q.theta) == pytest.approx((0.0, 0.0, 0.0), abs=1e-12)


# --- bad input -------------------------------------------------------------------------
@pytest.mark.parametrize(("sxy", "sth"), [(-0.1, 0.1), (0.1, -0.1), (0.0, 0.1), (0.1, 0.0)])
def test_sigmas_must_be_positive(sxy: float, sth: float) -> None:
    with pytest.raises(InputError, match="sigma"):
        PoseObservation("cam", "TM_1", 0.0, 0.0, 0.0, sxy, sth)


def test_observation_values_must_be_finite_and_nodes_named() -> None:
    with pytest.raises(InputError, match="finite"):
        PoseObservation("cam", "TM_1", math.nan, 0.0, 0.0, 0.1, 0.1)
    with pytest.raises(InputError, match="relative_to"):
        PoseObservation("cam", "TM_1", 0.0, 0.0, 0.0, 0.1, 0.1, relative_to="TM_1")
    with pytest.raises(InputError, match="subject"):
        PoseObservation("cam", "", 0.0, 0.0, 0.0, 0.1, 0.1)


def test_unknown_anchor() -> None:
    g = PoseGraph()
    g.add(obs("B", 1.0, 0.0, 0.0, 0.1, 0.1, relative_to="A"))
    with pytest.raises(InputError, match="unknown anchor"):
        g.solve(anchor="Z")


def test_anchor_is_needed_only_without_world_observations() -> None:
    edge = obs("B", 1.0, 0.0, 0.0, 0.1, 0.1, relative_to="A")
    with pytest.raises(InputError, match="anchor"):
        fuse_poses([edge])
    with pytest.raises(InputError, match="anchor"):
        fuse_poses([edge, obs("A", 0.0, 0.0, 0.0, 0.1, 0.1)], anchor="A")


def test_node_unlinked_to_the_frame_is_refused() -> None:
    observations = [obs("A", 0.0, 0.0, 0.0, 0.1, 0.1), obs("D", 1.0, 0.0, 0.0, 0.1, 0.1, "C")]
    with pytest.raises(InputError, match=r"\['C', 'D'\]"):
        fuse_poses(observations)


def test_empty_graph_and_unknown_subject() -> None:
    with pytest.raises(InputError):
        PoseGraph().solve()
    g = PoseGraph()
    g.add(obs("A", 0.0, 0.0, 0.0, 0.1, 0.1))
    with pytest.raises(InputError, match="unknown"):
        g.fused("B")
