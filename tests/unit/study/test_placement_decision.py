"""The placement advice decided face → conveyor → θ (`decide_placement`, Sec. 6.6)."""

from __future__ import annotations

import csv
from importlib import resources
from math import comb

import pytest

from transfertwin._errors import InputError
from transfertwin.ots import experiment_states, filter_theta_step
from transfertwin.study.fullstate import (
    decide_placement,
    level_line,
    placement_headline,
    state_table,
)


def _rows(obj: str, outcome, runs: int = 4, step: int = 30) -> list[dict[str, object]]:
    """`runs` rows per state of the θ-step grid; outcome(face, conveyor, θ, run) -> 0/1."""
    return [
        {"object_id": obj, "face": s.face, "conveyor": s.conveyor, "theta_deg": s.theta_deg,
         "success": outcome(s.face, s.conveyor, s.theta_deg, r), "status": "ok"}
        for s in filter_theta_step(experiment_states(), step)
        for r in range(runs)
    ]  # fmt: skip


def _tutorial_o18() -> list[dict[str, object]]:
    """The tutorial's o18 (θ-step 30°, 4 runs a state): every front run succeeded, 6 of
    the back runs did."""
    back_wins = {("left", 0), ("left", 180), ("both", 90), ("both", -90), ("right", 0),
                 ("both", 30)}  # fmt: skip
    return _rows("o18", lambda f, c, t, r: int(f == "front" or (r == 0 and (c, t) in back_wins)))


def _fisher_two_sided(a: int, n1: int, b: int, n2: int) -> float:
    """Fisher's exact test from the hypergeometric law by hand (sum of the tables no more
    likely than the one seen), independent of scipy."""
    k, n = a + b, n1 + n2

    def pmf(x: int) -> float:
        return comb(n1, x) * comb(n2, k - x) / comb(n, k)

    seen = pmf(a)
    lo, hi = max(0, k - n2), min(k, n1)
    return min(1.0, sum(pmf(x) for x in range(lo, hi + 1) if pmf(x) <= seen * (1 + 1e-7)))


def test_tutorial_o18_front_face_decided_any_conveyor_and_theta():
    rows = _tutorial_o18()
    d = decide_placement(state_table(rows), "o18")
    assert (d.face.verdict, d.conveyor.verdict, d.theta.verdict) == ("decided", "open", "open")
    assert (d.face.option("front").k, d.face.option("front").n) == (56, 56)
    assert (d.face.option("back").k, d.face.option("back").n) == (6, 56)
    assert placement_headline(d) == "Put it on its front face, on any conveyor, at any θ."
    line = level_line(d.face)
    assert line.startswith("Face: decided: front 56/56 against back 6/56")
    assert "p < 0.001" in line
    assert "does not matter (as far as n shows)" in level_line(d.conveyor)
    assert "does not matter (as far as n shows)" in level_line(d.theta)


def test_real_o1_says_front_face_and_no_exact_state():
    text = resources.files("transfertwin.data").joinpath("calibration_experiments.csv")
    with text.open(encoding="utf-8") as fh:
        rows = list(csv.DictReader(fh))
    d = decide_placement(state_table(rows), "o1")
    assert d.face.verdict == "decided"
    assert d.face.kept == ("front",)
    front, back = d.face.option("front"), d.face.option("back")
    assert (front.k, front.n, back.k, back.n) == (25, 31, 3, 23)
    headline = placement_headline(d)
    assert headline.startswith("Put it on its front face")
    assert "θ =" not in headline and "left belt" not in headline
    assert d.conveyor.verdict == d.theta.verdict == "open"
    assert "front 25/31 against back 3/23" in level_line(d.face)


def test_face_p_value_is_fishers_exact_test():
    text = resources.files("transfertwin.data").joinpath("calibration_experiments.csv")
    with text.open(encoding="utf-8") as fh:
        d = decide_placement(state_table(csv.DictReader(fh)), "o18")
    front, back = d.face.option("front"), d.face.option("back")
    assert back.p_adjusted == pytest.approx(_fisher_two_sided(front.k, front.n, back.k, back.n))


def test_a_tie_at_every_level_does_not_matter():
    d = decide_placement(state_table(_rows("o5", lambda f, c, t, r: int(r % 2 == 0))), "o5")
    assert [lv.verdict for lv in d.levels] == ["open", "open", "open"]
    assert placement_headline(d) == "Put it on either face, on any conveyor, at any θ."
    for lv in d.levels:
        assert "does not matter (as far as n shows)" in level_line(lv)
        assert lv.avoided == () and set(lv.kept) == {o.value for o in lv.options}


def test_conveyor_decided_within_the_chosen_face():
    rows = _rows("o7", lambda f, c, t, r: int(f == "front" and c == "both"))
    d = decide_placement(state_table(rows), "o7")
    assert d.face.kept == ("front",)
    assert d.conveyor.verdict == "decided" and d.conveyor.kept == ("both",)
    assert set(d.conveyor.avoided) == {"left", "right"}
    # the conveyor level counts the front face only: the back's failures are not pooled in
    assert d.conveyor.option("both").n == sum(
        1 for r in rows if r["face"] == "front" and r["conveyor"] == "both"
    )
    assert placement_headline(d) == (
        "Put it on its front face, centred across both belts, at any θ."
    )


def test_narrowed_conveyor_names_what_to_avoid():
    rows = _rows("o7", lambda f, c, t, r: int(c != "right"), runs=6)
    d = decide_placement(state_table(rows), "o7")
    assert d.face.verdict == "open"
    assert d.conveyor.verdict == "narrowed"
    assert d.conveyor.avoided == ("right",)
    assert "(not on the right belt)" in placement_headline(d)
    assert level_line(d.conveyor).startswith("Conveyor: narrowed down:")


def test_theta_decided_names_the_angle():
    rows = _rows("o2", lambda f, c, t, r: int(t == 90), runs=8)
    d = decide_placement(state_table(rows), "o2")
    assert d.theta.verdict == "decided" and d.theta.kept == ("90",)
    assert placement_headline(d).endswith("at θ = 90°.")


def test_only_one_face_run_is_said_so():
    rows = [r for r in _tutorial_o18() if r["face"] == "front"]
    d = decide_placement(state_table(rows), "o18")
    assert d.face.verdict == "single"
    assert "on its front face (the only one run)" in placement_headline(d)


def test_unknown_object_and_bad_alpha_are_refused():
    states = state_table(_tutorial_o18())
    with pytest.raises(InputError, match="no 'ok' experiment"):
        decide_placement(states, "o99")
    with pytest.raises(InputError, match="alpha"):
        decide_placement(states, "o18", alpha=1.0)


def test_to_dict_holds_every_level():
    d = decide_placement(state_table(_tutorial_o18()), "o18").to_dict()
    assert d["face"]["verdict"] == "decided"
    assert d["face"]["options"][0] == {"value": "front", "k": 56, "n": 56, "p_adjusted": None}
    assert d["conveyor"]["verdict"] == "open" and d["theta"]["verdict"] == "open"


def test_analyze_writes_the_advice_to_placement_json(tmp_path) -> None:
    import json

    from transfertwin.study.fullstate import analyze

    analyze(_tutorial_o18(), tmp_path)
    doc = json.loads((tmp_path / "placement.json").read_text(encoding="utf-8"))
    assert list(doc) == ["o18"]
    o18 = doc["o18"]
    assert o18["advice"] == "Put it on its front face, on any conveyor, at any θ."
    assert o18["face"]["verdict"] == "decided" and o18["face"]["kept"] == ["front"]
    assert o18["face"]["options"][1]["k"] == 6 and o18["face"]["options"][1]["n"] == 56
    assert o18["conveyor"]["verdict"] == o18["theta"]["verdict"] == "open"
