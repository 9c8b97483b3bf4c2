"""The twin's predictions in operation: states ranked by success share, then by the
Clopper–Pearson lower bound, then the study's state order (docs/architecture.md,
"Operation")."""

from __future__ import annotations

import pytest

from transfertwin.cps.dispatch._auction import Bid, choose
from transfertwin.cps.dispatch._predict import rank_states


def _rows(obj, face, conveyor, theta, outcomes, status="ok"):
    return [{"object_id": obj, "face": face, "conveyor": conveyor, "theta_deg": theta,
             "success": y, "status": status} for y in outcomes]  # fmt: skip


def test_states_rank_by_share_then_by_evidence_then_state_order():
    rows = [*_rows("o1", "front", "both", 90, [1, 1, 0, 1]),      # 3/4
            *_rows("o1", "back", "left", 0, [1, 1, 1, 1, 1, 1]),  # 6/6: more evidence
            *_rows("o1", "front", "left", 0, [1, 1]),             # 2/2
            *_rows("o1", "back", "right", 180, [1, 1]),           # 2/2, later in state order
            *_rows("o1", "front", "right", 0, [None], "invalid"),  # no 'ok' run: left out
            *_rows("o2", "front", "both", 90, [1])]               # another object
    ranked = rank_states(rows, "o1", "study s")
    assert [(p.face, p.conveyor, p.theta_deg, p.k, p.n) for p in ranked] == [
        ("back", "left", 0, 6, 6), ("front", "left", 0, 2, 2), ("back", "right", 180, 2, 2),
        ("front", "both", 90, 3, 4)]
    best = ranked[0]
    assert best.state == {"face": "back", "conveyor": "left", "theta_deg": 0}
    assert best.ci_low == pytest.approx(0.025 ** (1 / 6))  # CP lower bound of 6/6
    assert best.source == "study s" and rank_states(rows, "o9", "s") == []


def test_the_evaluator_picks_the_least_expected_time_per_successful_delivery():
    bids = [Bid("TM_2", {"TU_B": 100.0, "TU_C": 80.0}), Bid("TM_1", {"TU_B": 90.0})]
    assert choose(bids, "nearest-idle", 0.5)[:2] == ("TM_2", "TU_C")
    module, unit, cost = choose(bids, "predictive", 0.5)
    assert (module, unit, cost) == ("TM_2", "TU_C", 160.0)  # 80 s / p = 0.5
    assert choose([Bid("TM_2", {"TU_B": 90.0}), Bid("TM_1", {"TU_B": 90.0})],
                  "predictive", 0.0)[:2] == ("TM_1", "TU_B")  # a tie: the first by name
    with pytest.raises(ValueError, match="no bids"):
        choose([], "predictive", 1.0)
