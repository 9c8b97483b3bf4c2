"""`read_results`: a results table from a SQLite store, a CSV or a Parquet file.

CSV and Parquet tables need at least `REQUIRED_COLUMNS`. Real-experiment tables
(e.g. ``data/calibration_experiments.csv``) lack simulation columns and carry their
own; the reader:

- keeps extra columns after `RESULT_COLUMNS` (CSV: typed as int, float or text);
- fills a missing ``status`` with ``"ok"`` and a missing ``run`` with a running index
  from 0 per (object_id, face, conveyor, theta_deg), in file order;
- fills other missing columns as a store would read them back: None (int),
  NaN (float), ``""`` (text: str columns are never None).
"""

from __future__ import annotations

import csv
from collections import Counter
from pathlib import Path

import pyarrow as pa
import pyarrow.parquet as pq

from transfertwin._errors import InputError
from transfertwin.store._cells import PARSERS, infer_column
from transfertwin.store._schema import COLUMN_TYPES, KEY_COLUMNS, RESULT_COLUMNS, STATUSES
from transfertwin.store._sqlite import SQLiteResultStore

__all__ = ["REQUIRED_COLUMNS", "SQLITE_SUFFIXES", "read_results"]

#: Columns a CSV or Parquet result table must have.
REQUIRED_COLUMNS: tuple[str, ...] = ("object_id", "face", "conveyor", "theta_deg", "success")
SQLITE_SUFFIXES: tuple[str, ...] = (".sqlite", ".sqlite3", ".db")
_TABLE_SUFFIXES = (".csv", ".parquet")
_NON_NULL = frozenset({*KEY_COLUMNS, "status"})

Columns = dict[str, list[object]]


def read_results(path: str | Path) -> list[dict[str, object]]:
    """Read a results table into row dicts (`RESULT_COLUMNS` first, then extras).

    Args:
        path: A ``.sqlite``/``.sqlite3``/``.db`` result store, a ``.csv`` or a
            ``.parquet`` table.

    Returns:
        One dict per row; a store's rows in key order, a table's in file order.

    Raises:
        InputError: Unknown suffix, missing or unreadable file, missing required
            columns or a cell that does not fit its column type.
    """
    path = Path(path)
    suffix = path.suffix.lower()
    if suffix not in (*SQLITE_SUFFIXES, *_TABLE_SUFFIXES):
        known = ", ".join((*SQLITE_SUFFIXES, *_TABLE_SUFFIXES))
        raise InputError(f"{path}: unknown result table format {suffix or '(none)'!r}; use {known}")
    if not path.is_file():
        raise InputError(f"{path}: no such file")
    if suffix in SQLITE_SUFFIXES:
        with SQLiteResultStore(path, create=False) as store:
            return list(store.rows())
    columns = _read_csv(path) if suffix == ".csv" else _read_parquet(path)
    return _rows(path, columns)


def _read_csv(path: Path) -> Columns:
    try:
        with path.open(newline="", encoding="utf-8-sig") as f:
            reader = csv.reader(f)
            header = next(reader, None)
            if header is None:
                raise InputError(f"{path}: empty file, no header row")
            _check_unique(path, header)
            records = [record for record in reader if record]
    except (OSError, UnicodeDecodeError, csv.Error) as exc:
        raise InputError(f"{path}: cannot read CSV ({exc})") from None
    for i, record in enumerate(records, start=1):
        if len(record) != len(header):
            raise InputError(
                f"{path}: data row {i} has {len(record)} fields, the header {len(header)}"
            )
    return {name: [record[j] for record in records] for j, name in enumerate(header)}


def _read_parquet(path: Path) -> Columns:
    try:
        table = pq.read_table(path)
    except (OSError, pa.ArrowException) as exc:
        raise InputError(f"{path}: cannot read Parquet ({_first_line(exc)})") from None
    _check_unique(path, table.column_names)
    return {name: table.column(name).to_pylist() for name in table.column_names}


def _first_line(exc: BaseException) -> str:
    text = str(exc).strip()
    return text.splitlines()[0] if text else type(exc).__name__


def _check_unique(path: Path, names: list[str]) -> None:
    repeated = sorted(name for name, n in Counter(names).items() if n > 1)
    if repeated:
        raise InputError(f"{path}: repeated column(s) {', '.join(repeated)}")


def _convert(path: Path, name: str, values: list[object]) -> list[object]:
    """Parse one result column; InputError names the file, row and column."""
    parse = PARSERS[COLUMN_TYPES[name]]
    out = []
    for i, value in enumerate(values, start=1):
        try:
            cell = parse(value)
        except ValueError as exc:
            raise InputError(f"{path}: data row {i}, column {name}: {exc}") from None
        if name in _NON_NULL and cell in (None, ""):
            raise InputError(f"{path}: data row {i}, column {name}: empty cell")
        if name == "status" and cell not in STATUSES:
            raise InputError(
                f"{path}: data row {i}, column status: {cell!r} is not one of {', '.join(STATUSES)}"
            )
        out.append(cell)
    return out


def _running_run(columns: Columns, n: int) -> list[object]:
    """Run index from 0 per (object_id, face, conveyor, theta_deg), in file order."""
    seen: Counter[tuple[object, ...]] = Counter()
    runs: list[object] = []
    for i in range(n):
        state = tuple(columns[name][i] for name in KEY_COLUMNS[:4])
        runs.append(seen[state])
        seen[state] += 1
    return runs


def _rows(path: Path, table: Columns) -> list[dict[str, object]]:
    missing = [name for name in REQUIRED_COLUMNS if name not in table]
    if missing:
        raise InputError(f"{path}: missing required column(s) {', '.join(missing)}")
    n = len(table[REQUIRED_COLUMNS[0]])
    columns: Columns = {}
    for name in RESULT_COLUMNS:
        if name in table:
            columns[name] = _convert(path, name, table[name])
        elif name != "run":
            default = "ok" if name == "status" else PARSERS[COLUMN_TYPES[name]](None)
            columns[name] = [default] * n
    if "run" not in table:
        columns["run"] = _running_run(columns, n)
    names = [*RESULT_COLUMNS, *(name for name in table if name not in COLUMN_TYPES)]
    values = [columns[name] if name in columns else infer_column(table[name]) for name in names]
    return [dict(zip(names, row, strict=True)) for row in zip(*values, strict=True)]
