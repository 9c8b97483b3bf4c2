"""PropS's relative estimates (issue 28, item 4): the pose of one node in another's frame
with its covariance from the joint covariance, checked against sampling; a graph of
current estimates (`put`, `drop`)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from transfertwin import InputError
from transfertwin.cps.apps import Pose2D, PoseGraph, PoseObservation, fuse_poses


def test_relative_pose_and_covariance_match_sampling():
    unit = Pose2D(2.0, 6.0, math.pi / 2)
    module = unit.compose(Pose2D(0.004, -0.006, 0.02))
    obs = [PoseObservation("TU_A", "TU_A", unit.x, unit.y, unit.theta, 0.002, 0.002),
           PoseObservation("TM_1", "TM_1", module.x, module.y, module.theta, 0.02, 0.014)]
    sol = fuse_poses(obs)
    rel, cov = sol.relative("TU_A", "TM_1")
    assert (rel.x, rel.y, rel.theta) == pytest.approx((0.004, -0.006, 0.02), abs=1e-9)
    # two independent world priors: sample them and look at the relative pose
    rng = np.random.default_rng(4)
    sd_u, sd_m = np.array([0.002, 0.002, 0.002]), np.array([0.02, 0.02, 0.014])
    rels = []
    for _ in range(20000):
        u = unit.as_array() + rng.normal(0, 1, 3) * sd_u
        m = module.as_array() + rng.normal(0, 1, 3) * sd_m
        r = Pose2D(*u).inverse().compose(Pose2D(*m))
        rels.append(r.as_array())
    empirical = np.cov(np.array(rels).T)
    assert np.allclose(np.sqrt(np.diag(cov)), np.sqrt(np.diag(empirical)), rtol=0.05)


def test_a_camera_edge_dominates_and_is_correlated_with_the_world_path():
    unit = Pose2D(7.6, 6.1, math.pi / 2)
    err = Pose2D(-0.0031, 0.0122, 0.017)
    module = unit.compose(err)
    obs = [PoseObservation("TU_B", "TU_B", unit.x, unit.y, unit.theta, 0.002, 0.002),
           PoseObservation("TM_1", "TM_1", module.x + 0.015, module.y - 0.01,
                           module.theta + 0.01, 0.02, 0.014),
           PoseObservation("TU_B/camera", "TM_1", err.x, err.y, err.theta, 1e-4, 5e-4,
                           relative_to="TU_B")]  # fmt: skip
    sol = fuse_poses(obs)
    rel, cov = sol.relative("TU_B", "TM_1")
    sd = np.sqrt(np.diag(cov))
    assert (rel.x, rel.y, rel.theta) == pytest.approx((err.x, err.y, err.theta), abs=5e-5)
    assert sd[0] < 1e-4 and sd[1] < 1e-4 and sd[2] < 5e-4  # fused: tighter than the camera
    # the marginals alone (each ~2 mm: the unit's survey) without their correlation would
    # put the relative pose at ~3 mm
    naive = math.sqrt(sol.covariances["TU_B"][0, 0] + sol.covariances["TM_1"][0, 0])
    assert naive > 0.002 > 10 * sd[0]


def test_put_replaces_and_drop_removes():
    g = PoseGraph()
    g.put(PoseObservation("TM_1", "TM_1", 1.0, 2.0, 0.0, 0.02, 0.01))
    g.put(PoseObservation("TM_1", "TM_1", 3.0, 2.0, 0.0, 0.02, 0.01))
    assert len(g.observations) == 1 and g.fused("TM_1").x == pytest.approx(3.0)
    g.put(PoseObservation("cam", "TM_1", 0.0, 0.0, 0.0, 1e-4, 1e-4, relative_to="TU_A"))
    assert g.drop(lambda o: o.relative_to is not None) == 1
    assert len(g.observations) == 1
    with pytest.raises(InputError, match="unknown pose-graph node"):
        g.solution().relative("TU_A", "TM_1")
