"""An experiment's outcome in words, for what a person reads (the terminal, a replay's
caption): 'delivered and brought back in 9.75 s', 'failed on the way there: caught in the gap
after 7.60 s'. The machine form (status, y1, y2, success) stays in JSON and the store.

Where a failed transfer ended is read from its terminal state as the calibration's
sensitivity analysis reads it (`transfertwin.study.calibration.outcome`): caught in the gap
(its centre within reach of the TM's tip, not fallen), fallen below the belts, or failed
elsewhere on a belt.
"""

from __future__ import annotations

import math
from collections.abc import Mapping

from transfertwin.study.calibration import outcome

__all__ = ["outcome_text", "state_text", "status_text"]

#: How a failure ended, in words (keys: `transfertwin.study.calibration.outcome`).
_FAILURE_WORDS = {
    "stuck": "caught in the gap",
    "fell": "fell below the belts",
    "other": "stopped on a belt, short of the goal",
}

#: A conveyor value in words.
_CONVEYOR_WORDS = {"left": "left conveyor", "right": "right conveyor", "both": "both conveyors"}

#: A result that is not 'ok', in words (the message follows).
_STATUS_WORDS = {
    "invalid": "not run: the object did not settle into a start state",
    "unstable": "not determined: the simulation became unstable",
    "error": "not determined: the simulation failed",
}


def _seconds(value: object) -> str:
    """'7.60 s', or '' for a missing time."""
    if not isinstance(value, int | float) or math.isnan(value):
        return ""
    return f"{value:.2f} s"


def state_text(row: Mapping[str, object]) -> str:
    """The experiment of a result row in words: 'o1, front face, both conveyors, θ = 90°'."""
    conveyor = _CONVEYOR_WORDS.get(str(row["conveyor"]), str(row["conveyor"]))
    return f"{row['object_id']}, {row['face']} face, {conveyor}, θ = {row['theta_deg']}°"


def status_text(status: str, message: str = "") -> str:
    """A result's status in words: 'ok' reads 'ran', anything else what it means and its
    message (which cites the equation second)."""
    if status == "ok":
        return "ran"
    words = _STATUS_WORDS.get(status, f"not determined ({status})")
    return f"{words}; {message}" if message else words


def _failed(row: Mapping[str, object], leg_s: object) -> str:
    how = _FAILURE_WORDS[outcome(row)]
    after = _seconds(leg_s)
    return f"{how} after {after}" if after else how


def outcome_text(row: Mapping[str, object]) -> str:
    """One round trip E^V's outcome in words.

    Args:
        row: A result row (`ExperimentResult.row()` or a stored row): status, message, y1,
            y2, t_end_1_s, t_end_2_s, t_end_s and the terminal states as JSON lists.

    Returns:
        e.g. 'delivered and brought back in 9.75 s', 'failed on the way there: caught in
        the gap after 4.88 s', 'delivered in 4.90 s, failed on the way back: fell below
        the belts after 3.10 s', or the status in words when there is no outcome.
    """
    status = str(row.get("status"))
    if status != "ok" or row.get("y1") is None:
        return status_text(status, str(row.get("message") or ""))
    if row.get("y1") == 0:
        return "failed on the way there: " + _failed(row, row.get("t_end_1_s"))
    there = _seconds(row.get("t_end_1_s"))
    if row.get("y2") is None:
        return f"delivered in {there}" if there else "delivered"
    if row.get("y2") == 0:
        return f"delivered in {there}, failed on the way back: " + _failed(
            row, row.get("t_end_2_s")
        )
    total = _seconds(row.get("t_end_s"))
    return f"delivered and brought back in {total}" if total else "delivered and brought back"
