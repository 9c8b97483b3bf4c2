"""Outcomes in words: what `transfer` and `replay` print instead of status/y1/y2/success."""

from __future__ import annotations

import json

import pytest

from transfertwin.replay import outcome_text, state_text, status_text


def _row(**kw) -> dict[str, object]:
    """A result row; the terminal states are (11,) vectors (Eq. 5.4) as JSON."""
    base: dict[str, object] = {
        "object_id": "o1", "face": "back", "conveyor": "left", "theta_deg": -30, "status": "ok",
        "message": "", "y1": 1, "y2": 1, "success": 1, "t_end_1_s": 4.9, "t_end_2_s": 4.85,
        "t_end_s": 9.75, "state_end_1": "", "state_end_2": "",
    }  # fmt: skip
    base.update(kw)
    return base


def _state(x: float, z: float, sz: float = 0.04) -> str:
    return json.dumps([1.0, x, 0.0, z, 0.1, 0.05, sz, 0.0, 1.0, 0.0, 7.6])


def test_a_round_trip_that_worked_reads_delivered_and_brought_back() -> None:
    assert outcome_text(_row()) == "delivered and brought back in 9.75 s"


@pytest.mark.parametrize(
    ("end", "words"),
    [
        (_state(0.01, 0.11), "caught in the gap after 7.60 s"),
        (_state(0.01, -0.05), "fell below the belts after 7.60 s"),
        (_state(-0.40, 0.11), "stopped on a belt, short of the goal after 7.60 s"),
    ],
)
def test_a_failure_on_the_way_there_says_where_it_ended(end, words) -> None:
    row = _row(y1=0, y2=None, success=0, t_end_1_s=7.6, t_end_s=7.6, state_end_1=end)
    assert outcome_text(row) == f"failed on the way there: {words}"


def test_a_failure_on_the_way_back_says_the_delivery_worked() -> None:
    row = _row(y2=0, success=0, t_end_2_s=3.1, state_end_2=_state(0.0, 0.11))
    assert outcome_text(row) == (
        "delivered in 4.90 s, failed on the way back: caught in the gap after 3.10 s"
    )


def test_a_result_without_an_outcome_says_why_in_words_then_the_equation() -> None:
    row = _row(status="invalid", y1=None, y2=None, success=None,
               message="settled state is not a pre-transfer state (Eq. 6.1)")  # fmt: skip
    text = outcome_text(row)
    assert text.startswith("not run: the object did not settle into a start state")
    assert text.endswith("(Eq. 6.1)") and "None" not in text
    assert status_text("unstable").startswith("not determined")


def test_the_state_reads_as_words() -> None:
    assert state_text(_row(conveyor="both")) == "o1, back face, both conveyors, θ = -30°"
