"""Sensitivity analysis over real replays (real MuJoCo, a few rows, one run)."""

from __future__ import annotations

import math

import pytest

from tests.conftest import plain_body_proxy
from transfertwin.data import calibration_csv_path
from transfertwin.sim import SceneConfig
from transfertwin.store import read_results
from transfertwin.study.calibration import morris_screening, one_at_a_time, parse_factors


@pytest.fixture(scope="module")
def rows():
    real = read_results(calibration_csv_path())
    return [r for r in real if r["object_id"] == "o1" and r["face"] == "front"][:3]


@pytest.fixture(scope="module")
def plain(tmp_path_factory) -> dict[str, str]:
    """o1 mapped to its plain body: the shipped resting features catch by themselves."""
    return {"o1": plain_body_proxy(tmp_path_factory.mktemp("plain"))}


def test_a_height_step_shows_up_as_stuck_at_gap_failures(rows, plain):
    factors = parse_factors("tu_height_offset_m=0:0.04", SceneConfig())
    seen = []
    result = one_at_a_time(rows, base=SceneConfig(), factors=factors, levels=2, runs=1,
                           object_map=plain,
                           on_progress=lambda done, total: seen.append((done, total)))  # fmt: skip
    # The base scene equals the first level: it is simulated once (2 scenes x 3 rows).
    assert seen[-1] == (6, 6)
    flat, step = result.of("tu_height_offset_m")
    assert flat.share == result.base.share == 1.0
    assert (step.share, step.outcomes["stuck"], step.stuck_share) == (0.0, 3, 1.0)
    assert step.ci_low == 0.0 and step.ci_high == pytest.approx(0.708, abs=1e-3)
    assert step.signature["face"]["front"] == 0.0
    effect = result.effects()[0]
    assert (effect["factor"], effect["share_range"]) == ("tu_height_offset_m", 1.0)
    real = [r["success"] for r in rows]
    assert result.real["share"] == pytest.approx(sum(real) / 3)
    assert len(result.csv_rows()) == 3


def test_morris_screening_ranks_a_step_above_a_no_op(rows, plain):
    # feature_mu does nothing without a proxy's features: its elementary effects are 0.
    factors = parse_factors("tu_height_offset_m=0:0.04,feature_mu=0.2:1.0", SceneConfig())
    result = morris_screening(rows[:2], base=SceneConfig(), factors=factors, trajectories=2,
                              levels=2, runs=1, object_map=plain)  # fmt: skip
    assert result.points.shape == (6, 2)
    share = result.indices["share"]
    assert share["feature_mu"]["mu_star"] == 0.0
    assert share["tu_height_offset_m"]["mu_star"] > 0.5
    assert result.ranking()[0]["factor"] == "tu_height_offset_m"
    assert not math.isnan(result.outputs["stuck_rate"].max())
