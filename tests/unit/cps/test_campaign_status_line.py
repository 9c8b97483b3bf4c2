"""`cps campaign status` says how many held-out E^P the F0.5 before and after calibration rest
on and what their paired interval decides (a campaign of 40 E^P holds out a handful: its
"0.833 before, 1.000 after" read as a gain where the interval allows a loss)."""

from __future__ import annotations

from transfertwin.cli._cps_campaign import status_line

BASE = {"campaign": "c1", "state": "finished", "plant_experiments": 12, "floor_s": 76.0,
        "folder": "/w/c1"}  # fmt: skip
SUMMARY = {"f05_before": 0.833, "f05_after": 1.0, "significant_best": 0,
           "significant_worst": 0, "held_out": 4}  # fmt: skip


def _line(ci) -> str:
    return status_line({**BASE, "summary": {**SUMMARY, "f05_delta_ci": ci}})


def test_the_held_out_count_and_the_intervals_verdict_are_on_the_line():
    line = _line([-0.2, 0.5])
    assert "F0.5 on 4 held-out E^P 0.833 before, 1.000 after calibration" in line
    assert "(after − before [-0.200, +0.500]: undecided)" in line
    assert _line([0.05, 0.4]).count(": better)") == 1
    assert _line([-0.4, -0.01]).count(": worse)") == 1


def test_a_status_without_the_interval_still_reads():
    line = status_line({**BASE, "summary": {**SUMMARY, "held_out": None}})
    assert "F0.5 on held-out E^P 0.833 before, 1.000 after calibration;" in line
    assert status_line({"state": "none"}) == "campaign: none"
