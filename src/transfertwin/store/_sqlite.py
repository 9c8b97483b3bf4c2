"""`SQLiteResultStore`: the default result store, one SQLite file.

Layout (schema version 1): a ``meta`` table (key/value text: ``schema_version``,
``plan_hash``, ``plan_json``, ``created_utc``) and a ``results`` table with typed
columns and a PRIMARY KEY over (object_id, face, conveyor, theta_deg, run).

Durability: WAL journal, ``synchronous=NORMAL``, every `put` its own committed
transaction. A process killed with SIGKILL loses only the put in progress; the file
stays consistent, with no partial batch. On power loss the last commits may roll
back, but never partly.

Concurrency: put rows from ONE writer process (one store object, used from one
thread). Any number of readers may open the file at the same time
(``create=False``); each read sees every put committed before it started.
"""

from __future__ import annotations

import logging
import math
import sqlite3
import time
from collections.abc import Iterator, Mapping, Sequence
from contextlib import contextmanager
from datetime import UTC, datetime
from pathlib import Path

from transfertwin._errors import InputError
from transfertwin.store._base import ResultStore, StoredPlan, check_plan_args, plan_mismatch
from transfertwin.store._schema import (
    COLUMN_TYPES,
    FINISHED_COLUMN,
    KEY_COLUMNS,
    NULLABLE_INT_COLUMNS,
    RESULT_COLUMNS,
    SCHEMA_VERSION,
    STATUSES,
    ResultKey,
    normalize_row,
    utc_now_iso,
)

__all__ = ["SQLiteResultStore"]

log = logging.getLogger(__name__)

_BUSY_TIMEOUT_S = 30.0
_SQL_TYPES = {"str": "TEXT", "int": "INTEGER", "float": "REAL"}
_COLUMNS = (*RESULT_COLUMNS, FINISHED_COLUMN)
_FLOAT_AT = tuple(i for i, name in enumerate(_COLUMNS) if COLUMN_TYPES.get(name) == "float")
_SELECT_ROWS = f"SELECT {', '.join(_COLUMNS)} FROM results ORDER BY {', '.join(KEY_COLUMNS)}"
_INSERT_ROW = (
    f"INSERT OR IGNORE INTO results ({', '.join(_COLUMNS)}) "
    f"VALUES ({', '.join('?' for _ in _COLUMNS)})"
)


def _results_ddl() -> str:
    """CREATE TABLE statement of ``results`` from `COLUMN_TYPES`."""
    columns = []
    for name in RESULT_COLUMNS:
        kind = COLUMN_TYPES[name]
        nullable = kind == "float" or name in NULLABLE_INT_COLUMNS
        columns.append(f"{name} {_SQL_TYPES[kind]}{'' if nullable else ' NOT NULL'}")
    statuses = ", ".join(f"'{status}'" for status in STATUSES)
    return (
        f"CREATE TABLE results ({', '.join(columns)}, {FINISHED_COLUMN} TEXT NOT NULL, "
        f"CHECK (status IN ({statuses})), PRIMARY KEY ({', '.join(KEY_COLUMNS)})) WITHOUT ROWID"
    )


def _first_line(exc: BaseException) -> str:
    text = str(exc).strip()
    return text.splitlines()[0] if text else type(exc).__name__


def _journal_wal(conn: sqlite3.Connection) -> str:
    """Switch to WAL; the journal mode it got.

    Changing the journal mode needs a lock that SQLite does not wait for with the busy
    timeout: while another process creates the same file (a reader polling a study that is
    starting), the switch fails with "database is locked" at once. Retried within the busy
    timeout.
    """
    deadline = time.monotonic() + _BUSY_TIMEOUT_S
    while True:
        try:
            return str(conn.execute("PRAGMA journal_mode=WAL").fetchone()[0])
        except sqlite3.OperationalError as exc:
            if "locked" not in str(exc) or time.monotonic() > deadline:
                raise
            time.sleep(0.02)


def _connect(path: Path, create: bool) -> sqlite3.Connection:
    """Open the file in autocommit mode with WAL and synchronous=NORMAL."""
    if path.is_dir():
        raise InputError(f"{path}: is a folder, not a result database")
    if not path.exists():
        if not create:
            raise InputError(f"{path}: no such result database")
        if not path.parent.is_dir():
            raise InputError(f"{path}: folder {path.parent} does not exist")
    uri = path.resolve().as_uri() + ("?mode=rwc" if create else "?mode=rw")
    try:
        conn = sqlite3.connect(uri, uri=True, timeout=_BUSY_TIMEOUT_S, isolation_level=None)
    except sqlite3.Error as exc:
        raise InputError(f"{path}: cannot open result database ({_first_line(exc)})") from None
    try:
        mode = _journal_wal(conn)
        conn.execute("PRAGMA synchronous=NORMAL")
    except sqlite3.Error as exc:
        conn.close()
        raise InputError(f"{path}: not a usable SQLite database ({_first_line(exc)})") from None
    if str(mode).lower() != "wal":
        log.warning("%s: WAL journal not available, using %s", path, mode)
    return conn


class SQLiteResultStore(ResultStore):
    """A result store in one SQLite file (see the module docstring for durability).

    Args:
        path: The database file.
        create: Create the file (and its tables) when missing; with False a missing
            file is an error (readers).

    Raises:
        InputError: The file is missing (``create=False``), is not a SQLite database,
            is not a transfertwin result store, or has another schema version.
    """

    def __init__(self, path: str | Path, *, create: bool = True) -> None:
        self._path = Path(path)
        self._conn: sqlite3.Connection | None = _connect(self._path, create)
        try:
            self._init_schema(create)
        except sqlite3.Error as exc:
            self.close()
            raise InputError(
                f"{self._path}: unreadable result database ({_first_line(exc)})"
            ) from None
        except BaseException:
            self.close()
            raise

    @property
    def path(self) -> Path:
        """The database file."""
        return self._path

    def __repr__(self) -> str:
        return f"SQLiteResultStore({str(self._path)!r})"

    def _db(self) -> sqlite3.Connection:
        if self._conn is None:
            raise ValueError(f"operation on a closed result store ({self._path})")
        return self._conn

    @contextmanager
    def _write(self) -> Iterator[sqlite3.Connection]:
        """One write transaction: BEGIN IMMEDIATE … COMMIT, rolled back on any error."""
        conn = self._db()
        conn.execute("BEGIN IMMEDIATE")
        try:
            yield conn
            conn.execute("COMMIT")
        except BaseException:
            if conn.in_transaction:
                conn.execute("ROLLBACK")
            raise

    def _tables(self) -> set[str]:
        rows = self._db().execute("SELECT name FROM sqlite_master WHERE type = 'table'")
        return {name for (name,) in rows}

    def _init_schema(self, create: bool) -> None:
        if not self._tables() and create:
            with self._write() as conn:
                if not self._tables():
                    conn.execute("CREATE TABLE meta (key TEXT PRIMARY KEY, value TEXT NOT NULL)")
                    conn.execute(_results_ddl())
                    conn.execute(
                        "INSERT INTO meta VALUES ('schema_version', ?)", (str(SCHEMA_VERSION),)
                    )
        if not {"meta", "results"} <= self._tables():
            raise InputError(f"{self._path}: not a transfertwin result database")
        version = self._meta().get("schema_version")
        if version != str(SCHEMA_VERSION):
            raise InputError(
                f"{self._path}: result database has schema version {version}; "
                f"this transfertwin reads version {SCHEMA_VERSION}"
            )

    def _meta(self) -> dict[str, str]:
        return dict(self._db().execute("SELECT key, value FROM meta").fetchall())

    def _stored_plan(self) -> StoredPlan | None:
        meta = self._meta()
        if "plan_hash" not in meta:
            return None
        return StoredPlan(
            meta["plan_hash"],
            meta["plan_json"],
            datetime.fromisoformat(meta["created_utc"]),
            int(meta["schema_version"]),
        )

    def init_plan(self, plan_hash: str, plan_json: str) -> StoredPlan:
        """Bind the store to a plan (see `ResultStore.init_plan`)."""
        check_plan_args(plan_hash, plan_json)
        with self._write() as conn:
            stored = self._stored_plan()
            if stored is None:
                created = datetime.now(UTC)
                conn.executemany(
                    "INSERT INTO meta VALUES (?, ?)",
                    [
                        ("plan_hash", plan_hash),
                        ("plan_json", plan_json),
                        ("created_utc", created.isoformat(timespec="microseconds")),
                    ],
                )
                stored = StoredPlan(plan_hash, plan_json, created, SCHEMA_VERSION)
        if stored.plan_hash != plan_hash:
            raise plan_mismatch(str(self._path), stored.plan_hash, plan_hash)
        return stored

    def plan(self) -> StoredPlan | None:
        """The stored plan, or None (see `ResultStore.plan`)."""
        return self._stored_plan()

    def put(self, rows: Sequence[Mapping[str, object]]) -> int:
        """Insert-or-ignore rows by key in one committed transaction (see `ResultStore.put`)."""
        self._db()
        if isinstance(rows, Mapping):
            raise ValueError("put() takes a sequence of rows, got a single mapping")
        now = utc_now_iso()
        params = [_encode(normalize_row(row, now)) for row in rows]
        if not params:
            return 0
        with self._write() as conn:
            before = conn.total_changes
            conn.executemany(_INSERT_ROW, params)
            return conn.total_changes - before

    def done_keys(self) -> set[ResultKey]:
        """The keys of all stored rows."""
        return set(self._db().execute(f"SELECT {', '.join(KEY_COLUMNS)} FROM results"))

    def count(self) -> int:
        """The number of stored rows."""
        return int(self._db().execute("SELECT COUNT(*) FROM results").fetchone()[0])

    def count_by_status(self) -> dict[str, int]:
        """Stored rows per status, every status included."""
        counts = dict.fromkeys(STATUSES, 0)
        query = "SELECT status, COUNT(*) FROM results GROUP BY status"
        for status, n in self._db().execute(query):
            counts[status] = int(n)
        return counts

    def rows(self) -> Iterator[dict[str, object]]:
        """All stored rows ordered by key, streamed from one read snapshot."""
        cursor = self._db().execute(_SELECT_ROWS)
        return (_decode(values) for values in cursor)

    def close(self) -> None:
        """Close the connection; calling it again does nothing."""
        if self._conn is not None:
            self._conn.close()
            self._conn = None


def _encode(row: dict[str, object]) -> tuple[object, ...]:
    """SQL parameters of a normalised row: NaN floats become NULL."""
    return tuple(
        None if isinstance(value, float) and math.isnan(value) else value
        for value in (row[name] for name in _COLUMNS)
    )


def _decode(values: tuple[object, ...]) -> dict[str, object]:
    """A row dict from SQL values: NULL floats become NaN."""
    out = list(values)
    for i in _FLOAT_AT:
        if out[i] is None:
            out[i] = math.nan
    return dict(zip(_COLUMNS, out, strict=True))
