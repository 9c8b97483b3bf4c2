"""The console's readings in words (pure): JSON values as fields, angles in degrees, why an
asset does not answer, and which clock a time is on."""

from __future__ import annotations

import json

import pytest

from transfertwin.web._display import display_values, step_text, unreachable_text, value_text
from transfertwin.web._floor import order_rows


def test_fused_poses_read_as_places_not_json() -> None:
    poses = {"TM_1": {"x": 1.2, "y": 0.8, "theta": 1.5707963, "sd_x": 0.004, "sd_y": 0.004,
                      "sd_theta": 0.01, "reported": True}}  # fmt: skip
    assert (
        value_text("FusedPosesJson", json.dumps(poses)) == "TM_1 at (1.20, 0.80) m ± 0.4 cm, θ 90°"
    )
    assert value_text("FusedPosesJson", "{}") == "no poses yet"


def test_docking_errors_and_transfer_history_read_as_sentences() -> None:
    errors = {"TM_1": {"unit": "TU_B", "x_m": 0.0021, "y_m": -0.001, "theta_rad": 0.005}}
    assert value_text("DockingErrorsJson", json.dumps(errors)) == (
        "TM_1 at TU_B: x 2.1 mm, y -1.0 mm, θ 0.29°"
    )
    history = [{"operation": "op1", "target": "TU_B", "outcome": "delivered"},
               {"operation": "op2", "target": "TU_C", "outcome": "failed at delivery"}]  # fmt: skip
    assert value_text("TransferHistoryJson", json.dumps(history)) == (
        "2 transfers, the last failed at delivery at TU_C"
    )
    assert value_text("TransferHistoryJson", "[]") == "no transfers yet"


def test_an_assets_values_leave_the_kpis_to_their_panel_and_read_angles_in_degrees() -> None:
    shown = dict(display_values({"PoseTheta": 3.14159265, "KpisJson": '{"orders": 3}',
                                 "PossessedBy": "", "Busy": True, "Speed": 0.123456}))  # fmt: skip
    assert shown == {"PoseTheta": "180.0°", "PossessedBy": "–", "Busy": "yes", "Speed": "0.123"}
    assert not any("{" in text for text in shown.values())


@pytest.mark.parametrize(
    ("error", "words"),
    [("ConnectionRefusedError", "not answering: nothing listens at its address"),
     ("TimeoutError", "not answering: it did not answer in time"),
     ("SomethingNew", "not answering (SomethingNew)"), (None, "not answering")],
)  # fmt: skip
def test_why_an_asset_does_not_answer_is_said_in_words(error, words) -> None:
    assert unreachable_text(error).startswith(words)


def test_the_auctions_expected_time_says_it_is_modelled_floor_time() -> None:
    text = "assigned to TM_1 for TU_C (expected 225 s)"
    assert step_text(text) == "assigned to TM_1 for TU_C (expected 225 s of modelled floor time)"
    ops = [{"operation": "op1", "object": "o5", "history": [[1.0e9, text]]}]
    assert order_rows(ops, [])[0]["steps"][0]["text"].endswith("of modelled floor time)")


def test_an_objects_calibrated_predictions_read_as_its_best_and_worst_state() -> None:
    best = {"face": "front", "conveyor": "left", "theta_deg": 30, "share": 0.875,
            "ci_low": 0.473, "ci_high": 0.997}  # fmt: skip
    worst = {"face": "back", "conveyor": "both", "theta_deg": 90, "share": 0.0,
             "ci_low": 0.0, "ci_high": 0.369}  # fmt: skip
    doc = {"campaign": "8f5d3906a510", "leg": "operation", "best": best, "worst": worst,
           "states": [best, worst]}  # fmt: skip
    assert value_text("PredictionsJson", json.dumps(doc)) == (
        "best front face up, left conveyor, θ 30°: 88 % [47, 100] of the twin's runs "
        "(both legs); worst back face up, both conveyor, θ 90°: 0 % [0, 37] of the twin's "
        "runs; campaign 8f5d3906a510"
    )
    assert value_text("PredictionsJson", "{}") == "no campaign has predicted it yet"
    advised = {**doc, "advice": "Put it on its front face, on any conveyor, at any θ."}
    assert value_text("PredictionsJson", json.dumps(advised)).startswith(
        "Put it on its front face, on any conveyor, at any θ. best front face up"
    )
