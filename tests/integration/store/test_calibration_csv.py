"""`read_results` on the study's real calibration experiments (data/calibration_experiments.csv)."""

from __future__ import annotations

import csv
import math
from collections import Counter
from pathlib import Path

import pytest

from tests.unit.store.rows import assert_rows_equal
from transfertwin.store import KEY_COLUMNS, RESULT_COLUMNS, export_results, read_results

CALIBRATION_CSV = Path("/work/shared/data/calibration_experiments.csv")
pytestmark = pytest.mark.skipif(not CALIBRATION_CSV.is_file(), reason="shared data not present")


def raw_records() -> list[dict[str, str]]:
    """The file read with the csv module alone, as an independent reference."""
    with CALIBRATION_CSV.open(newline="", encoding="utf-8") as f:
        return list(csv.DictReader(f))


def test_reads_all_real_experiments() -> None:
    rows = read_results(CALIBRATION_CSV)
    assert len(rows) == 191
    assert sum(row["success"] for row in rows) == 128
    assert {row["status"] for row in rows} == {"ok"}


def test_fills_run_so_every_key_is_unique() -> None:
    rows = read_results(CALIBRATION_CSV)
    keys = [tuple(row[name] for name in KEY_COLUMNS) for row in rows]
    assert len(set(keys)) == len(rows)
    states = Counter(tuple(row[name] for name in KEY_COLUMNS[:4]) for row in rows)
    runs: dict[tuple[object, ...], list[object]] = {}
    for row in rows:
        runs.setdefault(tuple(row[name] for name in KEY_COLUMNS[:4]), []).append(row["run"])
    assert all(runs[state] == list(range(n)) for state, n in states.items())


def test_values_match_the_file_and_extras_are_kept() -> None:
    rows = read_results(CALIBRATION_CSV)
    for row, raw in zip(rows, raw_records(), strict=True):
        assert list(row)[: len(RESULT_COLUMNS)] == list(RESULT_COLUMNS)
        assert row["experiment_id"] == int(raw["experiment_id"])
        assert row["transfer_unit"] == raw["transfer_unit"]
        assert row["gap_area_cm2"] == float(raw["gap_area_cm2"])
        assert row["theta_deg"] == int(raw["theta_deg"])
        assert row["dock_err_x_mm"] == float(raw["dock_err_x_mm"])
        assert (row["seed"], row["y1"], row["y2"]) == (None, None, None)
        assert math.isnan(row["t_end_s"])


@pytest.mark.parametrize("suffix", [".csv", ".parquet"])
def test_real_table_round_trips_through_export(tmp_path: Path, suffix: str) -> None:
    rows = read_results(CALIBRATION_CSV)
    out = export_results(rows, tmp_path / f"calibration{suffix}")
    assert_rows_equal(read_results(out), rows)
