"""End to end on the study's real calibration experiments (Sec. 6.3, Table A.1).

The CSV has no status column (every row counts as 'ok') and one experiment per
state; expected counts are taken from the CSV itself with the csv module.
"""

from __future__ import annotations

import csv
import json
from collections import Counter
from pathlib import Path

import pytest

from transfertwin.report import analyze_and_report
from transfertwin.study.fullstate import STATES_COLUMNS

CALIBRATION_CSV = Path("/work/shared/data/calibration_experiments.csv")
OBJECTS = ("o1", "o18", "o23", "o32")


@pytest.fixture(scope="module")
def calibration_rows() -> list[dict[str, str]]:
    path = CALIBRATION_CSV
    if not path.exists():  # the packaged copy
        path = Path(__file__).parents[3] / "src" / "transfertwin" / "data" / path.name
    with path.open(newline="", encoding="utf-8") as fh:
        return list(csv.DictReader(fh))


def test_calibration_csv_end_to_end(calibration_rows: list[dict[str, str]], tmp_path: Path) -> None:
    assert len(calibration_rows) == 191
    analysis, report = analyze_and_report(
        calibration_rows, tmp_path, {"source": CALIBRATION_CSV.name}
    )
    assert analysis.object_ids == OBJECTS

    with (tmp_path / "states.csv").open(newline="") as fh:
        reader = csv.DictReader(fh)
        assert tuple(reader.fieldnames or ()) == STATES_COLUMNS
        states = list(reader)
    # Each state once, also a 'both' state (which lies in a left and a right series).
    unique = {(r["object_id"], r["face"], r["conveyor"], r["theta_deg"]): r for r in states}
    assert len(unique) == len(states)
    expected_n = Counter(
        (r["object_id"], r["face"], r["conveyor"], r["theta_deg"]) for r in calibration_rows
    )
    expected_k = Counter(
        (r["object_id"], r["face"], r["conveyor"], r["theta_deg"])
        for r in calibration_rows
        if r["success"] == "1"
    )
    assert {key: int(r["n"]) for key, r in unique.items()} == dict(expected_n)
    assert {key: int(r["k"]) for key, r in unique.items() if int(r["k"])} == dict(expected_k)
    assert sum(int(r["k"]) for r in unique.values()) == 128
    both = [r for r in states if r["conveyor"] == "both"]
    assert both and all(r["y_ma_left"] and r["y_ma_right"] for r in both)

    selection = json.loads((tmp_path / "selection.json").read_text())
    assert tuple(selection) == OBJECTS
    for obj in OBJECTS:
        for kind in ("best", "worst"):
            entry = selection[obj][kind]
            key = (obj, entry["face"], entry["conveyor"], str(entry["theta_deg"]))
            assert (
                entry["n"] == expected_n[key]
                and entry["p_hat"] == expected_k[key] / expected_n[key]
            )
            assert 0.0 <= entry["ci_low"] <= entry["p_hat"] <= entry["ci_high"] <= 1.0
        assert selection[obj]["best"]["y_ma"] >= selection[obj]["worst"]["y_ma"]

    text = report.read_text(encoding="utf-8")
    for obj in OBJECTS:
        assert f'alt="binary_{obj}"' in text and f'alt="full_state_{obj}"' in text
    assert text.count('<img src="data:image/png;base64,') == 2 + 2 * len(OBJECTS)
