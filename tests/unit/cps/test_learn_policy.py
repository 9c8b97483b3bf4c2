"""The predictive policy's learning (`cps.dispatch._learn`) and ranking (`cps.dispatch._predict`)
where the existing examples give the same answer either way: a fallback that the counted
failed pick-up changes, counts that accumulate, a leg after one that did not run, the
rounding of the posteriors; the documented constants pinned by value (docs/architecture.md,
"Learning from the floor's transfers" and "The twin's predictions"); the ranking of a study
store and its single-run states; learning alone (`uninformed`), a flat prior on both legs.

Expected values are worked by hand from the Beta–binomial posterior mean (w·m + k)/(w + n)
of docs/architecture.md: the delivery's prior m = (k_V + ½)/(n_V + 1), w = min(n_V, 4);
the pick-up's Laplace prior m = ½, w = 2; the face's other states at weight ½.
"""

from __future__ import annotations

import pytest

from tests.unit.store.rows import result_row
from transfertwin._errors import InputError
from transfertwin.cps.dispatch._learn import (
    _LAPLACE,
    FACE_POOL,
    LEGS,
    PRIOR_RUNS,
    fallback,
    posterior,
    record,
    rerank,
    tries,
    uninformed,
)
from transfertwin.cps.dispatch._predict import (
    DEFAULT_STATE,
    ON_THE_FLY_THETA_STEP,
    StatePrediction,
    rank_states,
    study_predictions,
)
from transfertwin.store import SQLiteResultStore

FRONT = {"face": "front", "conveyor": "both", "theta_deg": 0}


def _pred(face: str, conveyor: str, theta: int, k: int, n: int) -> dict:
    return {"face": face, "conveyor": conveyor, "theta_deg": theta, "k": k, "n": n}


def _leg(name: str, tr: dict | None) -> dict:
    leg: dict = {"leg": name, "unit": "TU_A"}
    if tr is not None:
        leg["transferring"] = tr
    return leg


def test_documented_constants_by_value() -> None:
    assert PRIOR_RUNS == 4.0  # "worth w = min(n_V, 4) plant runs"
    assert FACE_POOL == 0.5  # "on the same face count at half weight"
    assert _LAPLACE == (0.5, 2.0)  # "Laplace's (m = ½, w = 2)"
    assert LEGS == ("pick-up", "delivery")
    assert ON_THE_FLY_THETA_STEP == 30  # "the 28 states of the 30° grid"
    assert DEFAULT_STATE == {"face": "front", "conveyor": "left", "theta_deg": 0}


def test_the_default_state_is_one_the_twin_can_predict() -> None:
    """The state an object is loaded in without the twin is in Eq. 6.7's set and in the
    on-the-fly grid, so every twin arm ranks it beside the states it could move to."""
    from transfertwin.ots import experiment_states, filter_theta_step, state_index

    state_index(**DEFAULT_STATE)  # raises for a state outside the set
    grid = filter_theta_step(experiment_states(), ON_THE_FLY_THETA_STEP)
    assert (DEFAULT_STATE["face"], DEFAULT_STATE["conveyor"], DEFAULT_STATE["theta_deg"]) in {
        (s.face, s.conveyor, s.theta_deg) for s in grid}


def test_the_fallback_changes_once_the_failed_pick_up_is_counted() -> None:
    """Without the failure front/left would stay ahead (p 0.45 against 0.4167); counted on
    the front face at half weight it drops to 0.36 and the back face (7 of 8) wins."""
    preds = [_pred("front", "both", 0, 4, 4), _pred("front", "left", 90, 4, 4),
             _pred("back", "both", 0, 7, 8)]  # fmt: skip
    ranked = rerank(preds, {})
    assert [(p["face"], p["conveyor"]) for p in ranked][1:] == [("front", "left"), ("back", "both")]
    assert ranked[1]["p"] == pytest.approx(0.5 * 0.9, abs=1e-6)
    assert ranked[2]["p"] == pytest.approx(0.5 * 7.5 / 9, abs=1e-6)
    assert fallback(preds, {}, preds[0]) == {"face": "back", "conveyor": "both", "theta_deg": 0}


def test_the_fallback_adds_one_failure_to_the_failures_already_counted() -> None:
    """Two earlier front/both pick-ups (one failed) plus the hypothetical one: front/left's
    pick-up falls to (1 + ½·1)/(2 + ½·3) = 0.4286, p 0.3857 < back's 0.4167. Without the
    hypothetical failure it is (1 + ½)/(2 + 1) = 0.5, p 0.45 (front/left), and with the tries
    set to 1 instead of one more, (1 + ½)/(2 + ½) = 0.6."""
    preds = [_pred("front", "both", 0, 4, 4), _pred("front", "left", 90, 4, 4),
             _pred("back", "both", 0, 7, 8)]  # fmt: skip
    ev = {"pick-up": {"front/both/0": [1, 2]}}
    assert fallback(preds, ev, preds[0])["face"] == "back"
    assert ev == {"pick-up": {"front/both/0": [1, 2]}}  # the evidence is not changed


def test_successes_and_tries_accumulate_over_operations() -> None:
    ev: dict = {}
    ok = {"legs": [_leg("pick-up", {"y": 1, "valid": True})]}
    for _ in range(3):
        assert record(ev, "o6", FRONT, ok)
    record(ev, "o6", FRONT, {"legs": [_leg("pick-up", {"y": 0, "valid": True})]})
    assert ev == {"o6": {"pick-up": {"front/both/0": [3, 4]}}}
    p = posterior(_pred("front", "both", 0, 1, 1), ev["o6"])
    assert p["p_pickup"] == pytest.approx((2 * 0.5 + 3) / (2 + 4))
    assert p["p_delivery"] == pytest.approx(1.5 / 2)  # n_V = 1 < 4: worth one run, no data


def test_a_leg_after_one_that_did_not_run_still_counts() -> None:
    result = {"legs": [_leg("pick-up", None), _leg("unknown-leg", {"y": 1, "valid": True}),
                       _leg("delivery", {"y": 1, "valid": True})]}  # fmt: skip
    assert tries(result, FRONT) == [("delivery", FRONT, 1)]


def test_posteriors_are_rounded_to_six_decimals() -> None:
    ranked = rerank([_pred("front", "both", 0, 0, 2)], {"pick-up": {"front/both/0": [0, 1]}})
    assert ranked[0]["p_pickup"] == 0.333333  # 1/3
    assert ranked[0]["p_delivery"] == 0.166667  # (0 + ½)/(2 + 1)
    assert ranked[0]["p"] == 0.055556


def _rows(obj: str, face: str, conveyor: str, theta: int, outcomes: list[int]) -> list[dict]:
    return [result_row(obj, face, conveyor, theta, run=i, success=y, y1=y, y2=y)
            for i, y in enumerate(outcomes)]  # fmt: skip


def test_a_state_with_one_ok_run_is_ranked_with_its_interval() -> None:
    ranked = rank_states(_rows("o1", "front", "left", 0, [1]), "o1", "s")
    assert [(p.k, p.n, p.share) for p in ranked] == [(1, 1, 1.0)]
    assert ranked[0].ci_low == pytest.approx(0.025) and ranked[0].ci_high == 1.0
    assert ranked[0].as_dict() == {"face": "front", "conveyor": "left", "theta_deg": 0, "n": 1,
                                   "k": 1, "share": 1.0, "ci_low": ranked[0].ci_low,
                                   "ci_high": 1.0, "source": "s", "leg": "round-trip",
                                   "k_pickup": None}  # fmt: skip


def test_study_predictions_rank_the_objects_states_in_a_store(tmp_path) -> None:
    db = tmp_path / "study.sqlite"
    with SQLiteResultStore(db) as store:
        store.put([*_rows("o1", "front", "left", 0, [1, 0]), *_rows("o1", "back", "both", 90, [1]),
                   *_rows("o2", "front", "left", 0, [1])])  # fmt: skip
    ranked = study_predictions(db, "o1")
    assert all(isinstance(p, StatePrediction) for p in ranked)
    assert [(p.face, p.conveyor, p.theta_deg, p.k, p.n) for p in ranked] == [
        ("back", "both", 90, 1, 1), ("front", "left", 0, 1, 2)]  # fmt: skip
    assert {p.source for p in ranked} == {"study study.sqlite"}
    assert ranked[1].ci_high == pytest.approx(0.975**0.5)  # CP 95 % of 1/2: B(2, 1) = x²
    assert study_predictions(db, "o9") == []
    assert sorted(p.name for p in tmp_path.iterdir()) == ["study.sqlite"]
    with pytest.raises(InputError, match="no such result database"):  # never created
        study_predictions(tmp_path / "missing.sqlite", "o1")
    assert not (tmp_path / "missing.sqlite").exists()


def test_learning_alone_ranks_the_grid_from_a_flat_prior() -> None:
    """A state the twin did not simulate (n = 0) has Laplace's prior (m = ½, w = 2) on both
    legs: ½ · ½ without evidence, (2·½ + 1)/(2 + 1) = 2/3 after one delivery."""
    grid = [{"face": "front", "conveyor": "both", "theta_deg": 0.0},
            {"face": "back", "conveyor": "left", "theta_deg": 30}]  # fmt: skip
    preds = uninformed(grid)
    assert preds == [
        {"face": "front", "conveyor": "both", "theta_deg": 0, "k": 0, "n": 0, "share": None,
         "source": "none"},
        {"face": "back", "conveyor": "left", "theta_deg": 30, "k": 0, "n": 0, "share": None,
         "source": "none"},
    ]  # fmt: skip
    assert type(preds[0]["theta_deg"]) is int
    assert posterior(preds[0], {}) == {"p_pickup": 0.5, "p_delivery": 0.5, "p": 0.25}
    ev = {"delivery": {"back/left/30": [1, 1]}}
    assert posterior(preds[1], ev)["p_delivery"] == pytest.approx(2 / 3)
    assert [p["face"] for p in rerank(preds, ev)] == ["back", "front"]
