"""Both legs predicted by the twin: an 'operation' prediction (`cps.dispatch._predict`:
k_pickup of n runs picked up, k of them delivered) gives each leg its own prior
(`cps.dispatch._learn.twin_priors`), and a study store's plan says which legs it predicts.

Expected values worked by hand from (k + ½)/(n + 1), w = min(n, 4) (docs/architecture.md,
"Learning from the floor's transfers")."""

from __future__ import annotations

import json

import pytest

from tests.unit.store.rows import result_row
from transfertwin.cps.dispatch._learn import posterior, rerank, twin_priors
from transfertwin.cps.dispatch._predict import rank_states, study_predictions
from transfertwin.store import SQLiteResultStore


def _op(face: str, theta: int, k_pickup: int, k: int, n: int = 4) -> dict:
    return {"face": face, "conveyor": "both", "theta_deg": theta, "k": k, "n": n,
            "leg": "operation", "k_pickup": k_pickup}  # fmt: skip


def _rows(face: str, theta: int, outcomes: list[tuple[int, int | None]]) -> list[dict]:
    return [result_row("o1", face, "left", theta, run=i, y1=y1, y2=y2,
                       success=int(y1 == 1 and y2 == 1))
            for i, (y1, y2) in enumerate(outcomes)]  # fmt: skip


def test_an_operation_gives_the_pick_up_and_the_delivery_their_own_priors() -> None:
    pri = twin_priors(_op("front", 0, k_pickup=2, k=1))
    assert pri["pick-up"] == pytest.approx((2.5 / 5, 4.0))  # 2 of 4 picked up
    assert pri["delivery"] == pytest.approx((1.5 / 3, 2.0))  # 1 of the 2 delivered
    # a round trip predicts the delivery only; a pick-up study the pick-up only
    rt = {"face": "front", "conveyor": "both", "theta_deg": 0, "k": 3, "n": 4}
    assert twin_priors(rt) == {"pick-up": (0.5, 2.0), "delivery": (3.5 / 5, 4.0)}
    pu = {**rt, "leg": "pick-up", "k_pickup": 3}
    assert twin_priors(pu) == {"pick-up": (3.5 / 5, 4.0), "delivery": (0.5, 2.0)}
    # no pick-up succeeded in the twin: the delivery was never tried, Laplace's prior
    assert twin_priors(_op("back", 0, k_pickup=0, k=0))["delivery"] == (0.5, 2.0)


def test_the_twins_pick_up_prediction_decides_between_equal_operations() -> None:
    """Two states with the same share of whole operations (2 of 4): the one the twin
    picks up every time ranks first (p = 0.9 · 0.5 against 0.5 · 0.833)."""
    safe, risky = _op("front", 0, k_pickup=4, k=2), _op("back", 90, k_pickup=2, k=2)
    assert posterior(safe, {})["p"] == pytest.approx(4.5 / 5 * 2.5 / 5)
    assert posterior(risky, {})["p"] == pytest.approx(2.5 / 5 * 2.5 / 3)
    assert [p["face"] for p in rerank([risky, safe], {})] == ["front", "back"]
    # the floor's failed pick-ups of the safe state overturn the twin's
    evidence = {"pick-up": {"front/both/0": [0, 6]}}
    assert [p["face"] for p in rerank([risky, safe], evidence)] == ["back", "front"]


def test_operation_rows_count_their_pick_ups() -> None:
    rows = _rows("front", 0, [(1, 1), (1, 0), (0, None), (1, 1)])
    (pred,) = rank_states(rows, "o1", "s", "operation")
    assert (pred.n, pred.k_pickup, pred.k, pred.leg) == (4, 3, 2, "operation")
    (rt,) = rank_states(rows, "o1", "s")  # a round trip's rows: no pick-up count
    assert (rt.k_pickup, rt.leg) == (None, "round-trip")


def test_a_study_store_predicts_the_legs_of_its_plan(tmp_path) -> None:
    db = tmp_path / "op.sqlite"
    with SQLiteResultStore(db) as store:
        store.init_plan("a" * 64, json.dumps({"objects": ["o1"], "leg": "operation"}))
        store.put(_rows("front", 0, [(1, 1), (1, 0)]))
    (pred,) = study_predictions(db, "o1")
    assert (pred.leg, pred.k_pickup, pred.k, pred.n) == ("operation", 2, 1, 2)


def test_the_plan_says_per_leg_what_the_twin_predicted() -> None:
    from transfertwin.cps.dispatch import twin_words

    op = {**_op("front", 0, k_pickup=3, k=2), "source": "virtual experiments"}
    assert twin_words(op) == ("twin: picked up in 3 of 4 runs, delivered in 2 of 3 "
                              "(virtual experiments)")  # fmt: skip
    rt = {"k": 3, "n": 4, "source": "study s.sqlite"}
    assert twin_words(rt) == "twin: there and back in 3 of 4 runs (study s.sqlite)"
