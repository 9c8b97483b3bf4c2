"""An on-the-fly prediction sampled adaptively (`[operation] sampling = "adaptive"`): bounded
by the exhaustive prediction's number of experiments, runs spent on the states that race for
best and worst, the same rows for the same seed."""

from __future__ import annotations

import pytest

from transfertwin.cps.dispatch import ADAPTIVE_MAX_FACTOR, virtual_predictions


def _table(preds) -> list[tuple]:
    return [(p.face, p.conveyor, p.theta_deg, p.k, p.n, p.k_pickup) for p in preds]


def test_adaptive_predictions_are_bounded_focused_and_repeatable():
    runs = 2
    exhaustive = virtual_predictions("o1", runs, 3)
    adaptive = virtual_predictions("o1", runs, 3, sampling="adaptive")
    # (n counts a state's valid runs: an invalid pre-transfer state is not counted)
    assert max(p.n for p in exhaustive) == runs and len(exhaustive) == 28
    # the grid's states (one whose single run was invalid is not listed), none more than
    # the cap, no more runs in all
    grid = {(p.face, p.conveyor, p.theta_deg) for p in exhaustive}
    assert {(p.face, p.conveyor, p.theta_deg) for p in adaptive} <= grid
    assert len(adaptive) >= len(grid) - 2
    assert max(p.n for p in adaptive) <= ADAPTIVE_MAX_FACTOR * runs
    assert sum(p.n for p in adaptive) <= 28 * runs
    # the runs went where the race is: some state got more than the exhaustive share
    assert max(p.n for p in adaptive) > runs
    assert "adaptive" in adaptive[0].source and "adaptive" not in exhaustive[0].source
    # both legs predicted, as the exhaustive prediction does
    assert all(p.leg == "operation" and p.k_pickup is not None for p in adaptive)
    assert _table(virtual_predictions("o1", runs, 3, sampling="adaptive")) == _table(adaptive)


def test_an_unknown_sampling_is_refused():
    with pytest.raises(ValueError, match="one of exhaustive, adaptive"):
        virtual_predictions("o1", 1, 0, sampling="random")
