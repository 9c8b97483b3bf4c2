"""`export_results`: a results table to CSV or Parquet, written atomically.

Columns: `RESULT_COLUMNS`, then the extra columns of the first row in their order
(e.g. ``finished_utc`` from a store, ``experiment_id`` from a real-experiment table).
A row that lacks a column gets an empty cell; a row with a column outside the header
is a programming error (ValueError).

- CSV: UTF-8, header row, floats written with `repr` (exact round trip), None and NaN
  written as empty cells.
- Parquet: a typed, nullable schema from `COLUMN_TYPES` (str -> string, int -> int64,
  float -> float64, NaN written as null); extra columns typed from the first batch.

The table goes to a temporary file in the target folder, then `os.replace` moves it
into place: a failure leaves no partial file behind.
"""

from __future__ import annotations

import csv
import math
import os
import uuid
from collections.abc import Iterable, Iterator, Mapping
from itertools import chain, islice
from numbers import Integral, Real
from pathlib import Path

import pyarrow as pa
import pyarrow.parquet as pq

from transfertwin._errors import InputError
from transfertwin.store._schema import COLUMN_TYPES, FINISHED_COLUMN, RESULT_COLUMNS

__all__ = ["EXPORT_SUFFIXES", "export_results"]

EXPORT_SUFFIXES = (".csv", ".parquet")
_BATCH_ROWS = 65_536
_ARROW_TYPES = {"str": pa.string(), "int": pa.int64(), "float": pa.float64()}
_KNOWN_EXTRA_TYPES = {FINISHED_COLUMN: pa.string()}

Row = Mapping[str, object]


def export_results(rows: Iterable[Row], out_path: str | Path) -> Path:
    """Write a results table to ``.csv`` or ``.parquet`` (chosen by the suffix).

    Args:
        rows: Row mappings, e.g. `ResultStore.rows()` or `read_results(...)`; streamed.
        out_path: Target file; its folder must exist. An existing file is replaced.

    Returns:
        The written path.

    Raises:
        InputError: Unknown suffix, missing folder, or the file cannot be written.
        ValueError: A row has a column outside the header or a value of the wrong type.
    """
    path = Path(out_path)
    suffix = path.suffix.lower()
    if suffix not in EXPORT_SUFFIXES:
        raise InputError(
            f"{path}: unknown result format {suffix or '(none)'!r}; use .csv or .parquet"
        )
    if not path.parent.is_dir():
        raise InputError(f"{path}: folder {path.parent} does not exist")
    if path.is_dir():
        raise InputError(f"{path}: is a folder")
    header, it = _header(rows)
    write = _write_csv if suffix == ".csv" else _write_parquet
    try:
        tmp = _create_temporary(path)
    except OSError as exc:
        raise InputError(f"{path}: cannot write ({exc.strerror or exc})") from None
    try:
        write(it, header, tmp)
        os.replace(tmp, path)
    except OSError as exc:
        tmp.unlink(missing_ok=True)
        raise InputError(f"{path}: cannot write ({exc.strerror or exc})") from None
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise
    return path


def _create_temporary(path: Path) -> Path:
    """A new empty file next to `path` (permissions from the umask, unlike mkstemp)."""
    while True:
        tmp = path.with_name(f".{path.name}.{uuid.uuid4().hex[:12]}.tmp")
        try:
            tmp.open("xb").close()
        except FileExistsError:
            continue
        return tmp


def _header(rows: Iterable[Row]) -> tuple[tuple[str, ...], Iterator[Row]]:
    """Columns from the first row, and an iterator over all rows."""
    it = iter(rows)
    first = next(it, None)
    if first is None:
        return RESULT_COLUMNS, iter(())
    if not isinstance(first, Mapping):
        raise ValueError(f"rows must be mappings, got {type(first).__name__}")
    extras = tuple(str(name) for name in first if name not in COLUMN_TYPES)
    return (*RESULT_COLUMNS, *extras), chain((first,), it)


def _values(row: Row, header: tuple[str, ...], known: frozenset[str]) -> list[object]:
    """The row's cells in header order; None where it lacks a column."""
    if not known.issuperset(row):
        unknown = [str(name) for name in row if name not in known]
        raise ValueError(f"row has column(s) outside the table header: {', '.join(unknown)}")
    return [row.get(name) for name in header]


def _csv_cell(value: object) -> str:
    if value is None:
        return ""
    if isinstance(value, Integral):
        return str(int(value))
    if isinstance(value, Real):
        number = float(value)
        return "" if math.isnan(number) else repr(number)
    return str(value)


def _write_csv(rows: Iterator[Row], header: tuple[str, ...], tmp: Path) -> None:
    with tmp.open("w", newline="", encoding="utf-8") as f:
        writer = csv.writer(f)
        writer.writerow(header)
        known = frozenset(header)
        for row in rows:
            writer.writerow([_csv_cell(v) for v in _values(row, header, known)])
        f.flush()
        os.fsync(f.fileno())


def _arrow_column(name: str, values: list[object], kind: pa.DataType | None) -> pa.Array:
    """One column as an Arrow array; NaN in a float result column becomes null."""
    if COLUMN_TYPES.get(name) == "float":
        values = [
            None if v is None or (isinstance(v, Real) and math.isnan(v)) else v for v in values
        ]
    try:
        return pa.array(values, type=kind)
    except (pa.ArrowException, TypeError, ValueError, OverflowError) as exc:
        raise ValueError(f"column {name!r}: cannot write value ({exc})") from None


def _write_parquet(rows: Iterator[Row], header: tuple[str, ...], tmp: Path) -> None:
    types: dict[str, pa.DataType | None] = {
        name: _ARROW_TYPES.get(COLUMN_TYPES.get(name, ""), _KNOWN_EXTRA_TYPES.get(name))
        for name in header
    }
    known = frozenset(header)
    writer: pq.ParquetWriter | None = None
    try:
        while batch := [_values(row, header, known) for row in islice(rows, _BATCH_ROWS)]:
            columns = list(zip(*batch, strict=True))
            arrays = [
                _arrow_column(name, list(col), types[name])
                for name, col in zip(header, columns, strict=True)
            ]
            if writer is None:
                for name, array in zip(header, arrays, strict=True):
                    types[name] = pa.string() if pa.types.is_null(array.type) else array.type
                arrays = [a.cast(types[n]) for n, a in zip(header, arrays, strict=True)]
                writer = pq.ParquetWriter(tmp, pa.schema([(n, types[n]) for n in header]))
            writer.write_table(pa.Table.from_arrays(arrays, names=list(header)))
        if writer is None:
            schema = pa.schema([(n, types[n] or pa.string()) for n in header])
            pq.write_table(schema.empty_table(), tmp)
    finally:
        if writer is not None:
            writer.close()
