"""The floor's own transfers update the twin's per-state predictions (`cps.dispatch._learn`)."""

from __future__ import annotations

import pytest

from transfertwin.cps.dispatch._learn import (
    FACE_POOL,
    PRIOR_RUNS,
    fallback,
    posterior,
    record,
    rerank,
    tries,
)


def _pred(face: str, conveyor: str, theta: int, k: int, n: int) -> dict:
    return {"face": face, "conveyor": conveyor, "theta_deg": theta, "k": k, "n": n,
            "share": k / n}  # fmt: skip


def _result(*legs: tuple[str, dict | None]) -> dict:
    out = []
    for name, tr in legs:
        leg = {"leg": name, "unit": "TU_A", "docking": {}}
        if tr is not None:
            leg["transferring"] = tr
        out.append(leg)
    return {"status": "x", "legs": out}


def leg_outcomes(result: dict) -> dict[str, tuple[int, int]]:
    """(successes, tries) per leg of `tries`, all states together."""
    out: dict[str, tuple[int, int]] = {}
    for leg, _, y in tries(result, {"face": "front", "conveyor": "both", "theta_deg": 0}):
        k, n = out.get(leg, (0, 0))
        out[leg] = (k + y, n + 1)
    return out


def test_a_leg_counts_every_try_that_ran_and_nothing_else():
    ok = {"y": 1, "valid": True}
    failed = {"y": 0, "valid": True}
    assert leg_outcomes(_result(("pick-up", ok), ("delivery", failed))) == {
        "pick-up": (1, 1), "delivery": (0, 1)}  # fmt: skip
    # taken back once, then delivered: two tries, one success
    retried = {"y": 1, "valid": True, "retries": [{"attempt": 1}]}
    assert leg_outcomes(_result(("pick-up", ok), ("delivery", retried)))["delivery"] == (1, 2)
    # taken back twice and failed: the last failure is in the retries already
    twice = {"y": 0, "valid": True, "retries": [{"attempt": 1}, {"attempt": 2}]}
    assert leg_outcomes(_result(("delivery", twice))) == {"delivery": (0, 2)}
    # a start state outside P_pre, a scan that refused, a module that died: no evidence
    assert leg_outcomes(_result(("pick-up", {"y": 0, "valid": False}))) == {}
    assert leg_outcomes(_result(("pick-up", None))) == {}
    assert leg_outcomes({"status": "failed while navigating", "reason": "offline"}) == {}


def test_the_twin_is_the_prior_of_the_delivery_and_laplace_that_of_the_pick_up():
    p = posterior(_pred("front", "both", 0, 4, 4), {})
    assert p["p_delivery"] == pytest.approx(4.5 / 5)  # (k + 1/2) / (n + 1)
    assert p["p_pickup"] == pytest.approx(0.5)
    assert p["p"] == pytest.approx(0.45)
    # the twin's 40 runs count as PRIOR_RUNS plant runs: one failure moves it visibly
    ev: dict = {}
    record(ev, "o6", {"face": "front", "conveyor": "both", "theta_deg": 0},
           _result(("pick-up", {"y": 1, "valid": True}), ("delivery", {"y": 0, "valid": True})))
    q = posterior(_pred("front", "both", 0, 40, 40), ev["o6"])
    m = 40.5 / 41
    assert q["p_delivery"] == pytest.approx(PRIOR_RUNS * m / (PRIOR_RUNS + 1))
    assert q["p_pickup"] == pytest.approx((1 + 1) / (2 + 1))


def test_failed_pick_ups_on_a_face_turn_the_ranking_to_the_other_face():
    """o6 on plant seed 7 (measured): every pick-up on its front face fails, on its back
    face it goes over; the twin prefers the front face slightly."""
    preds = [_pred("front", "both", 0, 4, 4), _pred("front", "left", 90, 4, 4),
             _pred("back", "both", 0, 3, 4)]  # fmt: skip
    assert rerank(preds, {})[0]["face"] == "front"
    ev: dict = {}
    for _ in range(2):
        assert record(ev, "o6", {"face": "front", "conveyor": "both", "theta_deg": 0},
                      _result(("pick-up", {"y": 0, "valid": True})))  # fmt: skip
    ranked = rerank(preds, ev["o6"])
    assert [(p["face"], p["conveyor"]) for p in ranked] == [
        ("back", "both"), ("front", "left"), ("front", "both")]  # fmt: skip
    # the untried front state shares the face's failures at half weight
    assert ranked[1]["p_pickup"] == pytest.approx(1 / (2 + FACE_POOL * 2))
    assert ranked[2]["p_pickup"] == pytest.approx(1 / (2 + 2))


def test_without_a_state_or_a_transfer_nothing_is_recorded_and_ties_keep_the_twins_order():
    ev: dict = {}
    assert not record(ev, "o1", None, _result(("pick-up", {"y": 1, "valid": True})))
    assert not record(ev, "o1", {"face": "front", "conveyor": "both", "theta_deg": 0},
                      _result(("pick-up", None)))  # fmt: skip
    assert ev == {}
    preds = [_pred("back", "right", 30, 2, 4), _pred("front", "left", -30, 2, 4)]
    assert [p["face"] for p in rerank(preds, ev)] == ["back", "front"]


def test_a_pick_up_tried_again_in_the_fallback_state_counts_each_try_in_its_own_state():
    front = {"face": "front", "conveyor": "both", "theta_deg": 0}
    back = {"face": "back", "conveyor": "both", "theta_deg": 0}
    result = {"loaded_state": back, "legs": [
        {"leg": "pick-up", "transferring": {"y": 1, "valid": True, "retries": [
            {"attempt": 1, "taken_back": True, "state": front}]}},
        {"leg": "delivery", "transferring": {"y": 1, "valid": True}}]}  # fmt: skip
    assert tries(result, front) == [("pick-up", front, 0), ("pick-up", back, 1),
                                    ("delivery", back, 1)]  # fmt: skip
    ev: dict = {}
    record(ev, "o6", front, result)
    assert ev == {"o6": {"pick-up": {"front/both/0": [0, 1], "back/both/0": [1, 1]},
                         "delivery": {"back/both/0": [1, 1]}}}  # fmt: skip


def test_the_fallback_is_the_best_state_once_the_planned_pick_up_has_failed():
    preds = [_pred("front", "both", 0, 4, 4), _pred("front", "left", 90, 4, 4),
             _pred("back", "both", 0, 3, 4)]  # fmt: skip
    # one failure on the front face at half weight leaves front/left ahead of the back face
    assert fallback(preds, {}, preds[0]) == {"face": "front", "conveyor": "left",
                                            "theta_deg": 90}  # fmt: skip
    # with a front pick-up failed already, the second one turns it to the back face
    ev = {"pick-up": {"front/left/90": [0, 1]}}
    best = rerank(preds, ev)[0]
    assert best["face"] == "front" and best["conveyor"] == "both"
    assert fallback(preds, ev, best)["face"] == "back"
    assert fallback(preds[:1], {}, preds[0]) is None
