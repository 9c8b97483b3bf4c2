"""`read_results` on small CSV tables: defaults, typing and one-line InputErrors."""

from __future__ import annotations

import math
from pathlib import Path

import pytest

from transfertwin import InputError
from transfertwin.store import RESULT_COLUMNS, read_results

REAL_HEADER = "experiment_id,object_id,theta_deg,face,conveyor,success,dock_err_x_mm,note"


def write(tmp_path: Path, text: str, name: str = "table.csv") -> Path:
    path = tmp_path / name
    path.write_text(text, encoding="utf-8")
    return path


def one_line_error(path: Path) -> str:
    with pytest.raises(InputError) as info:
        read_results(path)
    message = str(info.value)
    assert "\n" not in message
    assert str(path) in message
    return message


def test_real_experiment_table_gets_defaults_and_keeps_extras(tmp_path: Path) -> None:
    path = write(
        tmp_path,
        f"{REAL_HEADER}\n"
        "7,o1,-11,front,right,1,-8.5,a\n"
        "8,o1,-11,front,right,0,,b\n"
        "9,o1,12,front,right,1,2,\n"
        "10,o1,-11,front,right,1,1.0,c\n",
    )
    rows = read_results(path)
    assert [r["run"] for r in rows] == [0, 1, 0, 2]
    assert {r["status"] for r in rows} == {"ok"}
    assert list(rows[0]) == [*RESULT_COLUMNS, "experiment_id", "note"]
    first = rows[0]
    assert (first["object_id"], first["face"], first["conveyor"]) == ("o1", "front", "right")
    assert (first["theta_deg"], first["success"], first["experiment_id"]) == (-11, 1, 7)
    assert first["seed"] is None and first["y1"] is None and first["y2"] is None
    assert math.isnan(first["t_end_s"]) and first["message"] == ""
    assert math.isnan(rows[1]["dock_err_x_mm"]) and rows[2]["dock_err_x_mm"] == 2.0
    assert [r["note"] for r in rows] == ["a", "b", "", "c"]


def test_numeric_text_is_typed(tmp_path: Path) -> None:
    path = write(
        tmp_path,
        "object_id,face,conveyor,theta_deg,run,success,y1,t_end_s,status,ratio\n"
        "o1,back,both,3.0,1,,1, 2.5 ,invalid,0.5\n"
        "o1,back,both,3,2,0,,nan,ok,1\n",
    )
    a, b = read_results(path)
    assert (type(a["theta_deg"]), a["theta_deg"], a["success"], a["y1"]) == (int, 3, None, 1)
    assert a["t_end_s"] == 2.5 and math.isnan(b["t_end_s"])
    assert (a["status"], b["status"]) == ("invalid", "ok")
    assert (a["ratio"], b["ratio"]) == (0.5, 1.0)


def test_header_only_table_reads_as_no_rows(tmp_path: Path) -> None:
    assert read_results(write(tmp_path, "object_id,face,conveyor,theta_deg,success\n")) == []


def test_missing_required_columns_are_named(tmp_path: Path) -> None:
    message = one_line_error(write(tmp_path, "object_id,face,theta_deg\no1,front,0\n"))
    assert "missing required column(s) conveyor, success" in message


@pytest.mark.parametrize(
    ("row", "problem"),
    [
        ("o1,front,left,ten,1", "column theta_deg: 'ten' is not an integer"),
        ("o1,front,left,2.5,1", "column theta_deg: '2.5' is not an integer"),
        ("o1,front,left,,1", "column theta_deg: empty cell"),
        (",front,left,0,1", "column object_id: empty cell"),
        ("o1,front,left,0,yes", "column success: 'yes' is not an integer"),
        ("o1,front,left,0", "data row 1 has 4 fields, the header 5"),
    ],
)
def test_bad_cell_names_file_row_and_column(tmp_path: Path, row: str, problem: str) -> None:
    path = write(tmp_path, f"object_id,face,conveyor,theta_deg,success\n{row}\n")
    assert problem in one_line_error(path)


def test_unknown_status_is_refused(tmp_path: Path) -> None:
    path = write(
        tmp_path, "object_id,face,conveyor,theta_deg,success,status\no1,front,left,0,1,fine\n"
    )
    assert "'fine' is not one of ok, invalid, unstable, error" in one_line_error(path)


def test_repeated_column_is_refused(tmp_path: Path) -> None:
    path = write(tmp_path, "object_id,face,conveyor,theta_deg,success,face\no1,a,b,0,1,c\n")
    assert "repeated column(s) face" in one_line_error(path)


@pytest.mark.parametrize(
    ("name", "content", "problem"),
    [
        ("table.xlsx", b"x", "unknown result table format '.xlsx'"),
        ("table", b"x", "unknown result table format '(none)'"),
        ("table.csv", b"", "empty file"),
        ("table.csv", b"\xff\xfe\x00bad", "cannot read CSV"),
        ("table.parquet", b"not parquet at all", "cannot read Parquet"),
        ("table.sqlite", b"not a database, just text", "not a usable SQLite database"),
    ],
)
def test_unreadable_files_are_input_errors(
    tmp_path: Path, name: str, content: bytes, problem: str
) -> None:
    path = tmp_path / name
    path.write_bytes(content)
    assert problem in one_line_error(path)


@pytest.mark.parametrize("name", ["absent.csv", "absent.parquet", "absent.sqlite"])
def test_missing_file_is_an_input_error(tmp_path: Path, name: str) -> None:
    assert "no such file" in one_line_error(tmp_path / name)
    assert not (tmp_path / name).exists()
