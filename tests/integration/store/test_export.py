"""CSV and Parquet export: exact round trip through `read_results`, atomic writes."""

from __future__ import annotations

import csv
from collections.abc import Iterator
from pathlib import Path

import pyarrow as pa
import pyarrow.parquet as pq
import pytest

from tests.unit.store.rows import assert_rows_equal, result_row, tricky_rows
from transfertwin import InputError
from transfertwin.store import (
    FINISHED_COLUMN,
    RESULT_COLUMNS,
    MemoryResultStore,
    SQLiteResultStore,
    export_results,
    read_results,
)

SUFFIXES = (".csv", ".parquet")


@pytest.fixture
def stored_rows(tmp_path: Path) -> list[dict[str, object]]:
    with SQLiteResultStore(tmp_path / "study.sqlite") as store:
        store.put(tricky_rows())
        return list(store.rows())


@pytest.mark.parametrize("suffix", SUFFIXES)
def test_store_rows_round_trip(
    tmp_path: Path, stored_rows: list[dict[str, object]], suffix: str
) -> None:
    out = export_results(stored_rows, tmp_path / f"results{suffix}")
    assert out == tmp_path / f"results{suffix}"
    assert_rows_equal(read_results(out), stored_rows)
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted(["study.sqlite", out.name])


@pytest.mark.parametrize("suffix", SUFFIXES)
def test_store_iterator_exports_and_reimports_into_a_store(tmp_path: Path, suffix: str) -> None:
    source = MemoryResultStore()
    source.put([result_row(run=run, theta_deg=theta) for run in range(3) for theta in (-1, 1)])
    out = export_results(source.rows(), tmp_path / f"results{suffix}")
    target = MemoryResultStore()
    assert target.put(read_results(out)) == 6
    assert_rows_equal(list(target.rows()), list(source.rows()))


def test_csv_header_and_empty_cells(tmp_path: Path, stored_rows: list[dict[str, object]]) -> None:
    out = export_results(stored_rows, tmp_path / "results.csv")
    with out.open(newline="", encoding="utf-8") as f:
        header, *records = list(csv.reader(f))
    assert header == [*RESULT_COLUMNS, FINISHED_COLUMN]
    cells = [dict(zip(header, record, strict=True)) for record in records]
    (invalid,) = [row for row in cells if row["status"] == "invalid"]
    assert (invalid["y1"], invalid["t_end_s"], invalid["theta_deg"]) == ("", "", "-179")
    assert 'settled, "not" pre-transfer\nsecond line' in {row["message"] for row in cells}


def test_parquet_schema_is_typed_and_nullable(
    tmp_path: Path, stored_rows: list[dict[str, object]]
) -> None:
    out = export_results(stored_rows, tmp_path / "results.parquet")
    schema = pq.read_schema(out)
    assert schema.names == [*RESULT_COLUMNS, FINISHED_COLUMN]
    assert schema.field("theta_deg").type == pa.int64()
    assert schema.field("success").type == pa.int64()
    assert schema.field("t_end_s").type == pa.float64()
    assert schema.field("object_id").type == pa.string()
    assert all(field.nullable for field in schema)
    table = pq.read_table(out)
    assert table.column("t_end_s").null_count == 1  # NaN written as null
    assert table.column("y1").null_count == 1


@pytest.mark.parametrize("suffix", SUFFIXES)
def test_empty_export_reads_back_empty(tmp_path: Path, suffix: str) -> None:
    out = export_results([], tmp_path / f"results{suffix}")
    assert read_results(out) == []


@pytest.mark.parametrize("name", ["results.xlsx", "results", "results.csv.gz"])
def test_unknown_suffix_is_refused_and_writes_nothing(
    tmp_path: Path, stored_rows: list[dict[str, object]], name: str
) -> None:
    before = sorted(tmp_path.iterdir())
    with pytest.raises(InputError, match="unknown result format") as info:
        export_results(stored_rows, tmp_path / name)
    assert "\n" not in str(info.value)
    assert sorted(tmp_path.iterdir()) == before


def test_missing_folder_is_an_input_error(tmp_path: Path) -> None:
    with pytest.raises(InputError, match="does not exist"):
        export_results([result_row()], tmp_path / "absent" / "results.csv")


def failing_rows(n: int) -> Iterator[dict[str, object]]:
    yield from (result_row(run=run) for run in range(n))
    raise RuntimeError("producer failed")


@pytest.mark.parametrize("suffix", SUFFIXES)
def test_failure_mid_write_leaves_old_file_and_no_temporary(tmp_path: Path, suffix: str) -> None:
    out = tmp_path / f"results{suffix}"
    export_results([result_row(run=99)], out)
    old = out.read_bytes()
    with pytest.raises(RuntimeError, match="producer failed"):
        export_results(failing_rows(70_000), out)
    assert out.read_bytes() == old
    assert [p.name for p in tmp_path.iterdir()] == [out.name]


@pytest.mark.parametrize("suffix", SUFFIXES)
def test_row_with_column_outside_header_is_a_programming_error(tmp_path: Path, suffix: str) -> None:
    rows = [result_row(run=0), {**result_row(run=1), "surprise": 1}]
    with pytest.raises(ValueError, match="surprise") as info:
        export_results(rows, tmp_path / f"results{suffix}")
    assert not isinstance(info.value, InputError)
    assert list(tmp_path.iterdir()) == []


def test_parquet_batches_keep_extra_column_types(tmp_path: Path) -> None:
    rows = [
        {**result_row(run=run), "note": None if run < 70_000 else "late"} for run in range(70_010)
    ]
    out = export_results(rows, tmp_path / "results.parquet")
    back = read_results(out)
    assert len(back) == 70_010
    assert (back[0]["note"], back[-1]["note"]) == (None, "late")
