"""SQLite backend on real files: reopen, WAL, schema version, foreign files, readers."""

from __future__ import annotations

import sqlite3
from pathlib import Path

import pytest

from tests.unit.store.rows import assert_rows_equal, result_row, sort_key, tricky_rows
from transfertwin import InputError
from transfertwin.store import (
    SCHEMA_VERSION,
    PlanMismatch,
    SQLiteResultStore,
    read_results,
)


@pytest.fixture
def db(tmp_path: Path) -> Path:
    return tmp_path / "study.sqlite"


def one_line_error(path: Path, **kwargs: object) -> str:
    with pytest.raises(InputError) as info:
        SQLiteResultStore(path, **kwargs)  # type: ignore[arg-type]
    message = str(info.value)
    assert "\n" not in message and str(path) in message
    return message


def test_reopen_keeps_rows_and_plan(db: Path) -> None:
    with SQLiteResultStore(db) as store:
        plan = store.init_plan("hash-a", '{"n": 2}')
        store.put(tricky_rows())
        rows = list(store.rows())
    with SQLiteResultStore(db, create=False) as store:
        assert store.plan() == plan
        assert store.init_plan("hash-a", '{"n": 2}') == plan
        assert_rows_equal(list(store.rows()), rows)
        assert store.put(tricky_rows()) == 0
    assert_rows_equal(read_results(db), rows)


def test_other_plan_on_reopen_names_the_file(db: Path) -> None:
    with SQLiteResultStore(db) as store:
        store.init_plan("hash-a", "{}")
    with SQLiteResultStore(db) as store, pytest.raises(PlanMismatch, match="different study plan"):
        store.init_plan("hash-b", "{}")
    with SQLiteResultStore(db) as store:
        with pytest.raises(PlanMismatch) as info:
            store.init_plan("hash-b", "{}")
        assert str(db) in str(info.value)


def test_wal_journal_and_layout(db: Path) -> None:
    SQLiteResultStore(db).close()
    with sqlite3.connect(db) as conn:
        assert conn.execute("PRAGMA journal_mode").fetchone()[0] == "wal"
        meta = dict(conn.execute("SELECT key, value FROM meta"))
        assert meta == {"schema_version": str(SCHEMA_VERSION)}
        pk = [row[1] for row in conn.execute("PRAGMA table_info(results)") if row[5]]
        assert pk == ["object_id", "face", "conveyor", "theta_deg", "run"]
    conn.close()


def test_other_schema_version_is_refused(db: Path) -> None:
    SQLiteResultStore(db).close()
    conn = sqlite3.connect(db)
    with conn:
        conn.execute("UPDATE meta SET value = '99' WHERE key = 'schema_version'")
    conn.close()
    message = one_line_error(db)
    assert "schema version 99" in message and f"version {SCHEMA_VERSION}" in message


def test_non_sqlite_file_is_refused_and_left_alone(db: Path) -> None:
    db.write_text("object_id,face\no1,front\n", encoding="utf-8")
    assert "not a usable SQLite database" in one_line_error(db)
    assert db.read_text(encoding="utf-8") == "object_id,face\no1,front\n"


def test_foreign_sqlite_database_is_refused(db: Path) -> None:
    conn = sqlite3.connect(db)
    with conn:
        conn.execute("CREATE TABLE other (x INTEGER)")
    conn.close()
    assert "not a transfertwin result database" in one_line_error(db)


def test_missing_file_without_create_is_refused_and_not_created(db: Path) -> None:
    assert "no such result database" in one_line_error(db, create=False)
    assert not db.exists()


def test_missing_folder_and_folder_path_are_refused(tmp_path: Path) -> None:
    assert "does not exist" in one_line_error(tmp_path / "absent" / "study.sqlite")
    assert "is a folder" in one_line_error(tmp_path)


def test_empty_file_becomes_a_store(db: Path) -> None:
    db.touch()
    with SQLiteResultStore(db) as store:
        assert store.count() == 0


def test_reader_sees_committed_puts_while_writer_is_open(db: Path) -> None:
    with SQLiteResultStore(db) as writer, SQLiteResultStore(db, create=False) as reader:
        writer.put([result_row(run=0), result_row(run=1)])
        assert reader.count() == 2
        rows = reader.rows()
        assert sort_key(next(rows))[-1] == 0
        writer.put([result_row(run=2), result_row(run=3)])
        assert [sort_key(row)[-1] for row in rows] == [1]  # an open read keeps its snapshot
        assert reader.count() == 4
        assert reader.done_keys() == writer.done_keys()
