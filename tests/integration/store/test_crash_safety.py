"""A writer killed with SIGKILL leaves a consistent store that resumes the same plan."""

from __future__ import annotations

import os
import signal
import sqlite3
import subprocess
import sys
import time
from collections.abc import Callable
from pathlib import Path

import pytest

from tests.unit.store.rows import result_row
from transfertwin import InputError
from transfertwin.store import PlanMismatch, SQLiteResultStore

BATCH = 25  # rows per put
MIN_ROWS = 40 * BATCH  # kill once at least this many rows are committed
MAX_PUTS = 100_000  # the child stops by itself if it is never killed

# The child puts batches of rows with run = 0, 1, 2, ... and prints each batch index
# once its put has returned (committed).
CHILD = """
import sys
from transfertwin.store import RESULT_COLUMNS, SQLiteResultStore

path, batch, max_puts = sys.argv[1], int(sys.argv[2]), int(sys.argv[3])
base = dict.fromkeys(RESULT_COLUMNS)
base.update(object_id="o1", face="front", conveyor="left", theta_deg=0, seed=1,
            status="ok", message="m, \\"q\\"\\nline")
with SQLiteResultStore(path) as store:
    store.init_plan("plan-a", '{"plan": "a"}')
    for i in range(max_puts):
        store.put([dict(base, run=i * batch + j) for j in range(batch)])
        print(i, flush=True)
"""


def committed_rows(db: Path) -> int:
    """Rows committed so far, read by a concurrent reader (0 before the store exists)."""
    try:
        with SQLiteResultStore(db, create=False) as reader:
            return reader.count()
    except InputError:
        return 0


def wait_for(condition: Callable[[], bool], proc: subprocess.Popen[str], timeout_s: float) -> None:
    """Poll until the condition holds; fail early if the child exits."""
    deadline = time.monotonic() + timeout_s
    while not condition():
        assert proc.poll() is None, f"writer exited early: {proc.stderr.read()}"  # type: ignore[union-attr]
        assert time.monotonic() < deadline, "writer made no progress in time"
        time.sleep(0.005)


@pytest.fixture
def killed_writer(tmp_path: Path) -> tuple[Path, int]:
    """A db whose writer was SIGKILLed mid-run, and the last batch index it printed."""
    db = tmp_path / "study.sqlite"
    out = tmp_path / "child.out"
    with out.open("w") as stdout:
        proc = subprocess.Popen(
            [sys.executable, "-c", CHILD, str(db), str(BATCH), str(MAX_PUTS)],
            stdout=stdout, stderr=subprocess.PIPE, text=True,
        )  # fmt: skip
        try:
            wait_for(lambda: committed_rows(db) >= MIN_ROWS, proc, timeout_s=120)
            os.kill(proc.pid, signal.SIGKILL)
            proc.wait(timeout=60)
        finally:
            if proc.poll() is None:
                proc.kill()
                proc.wait()
            proc.stderr.close()  # type: ignore[union-attr]
    assert proc.returncode == -signal.SIGKILL
    printed = [int(line) for line in out.read_text().split()]
    assert printed == list(range(len(printed)))
    return db, len(printed)


def test_killed_writer_leaves_whole_batches_only(killed_writer: tuple[Path, int]) -> None:
    db, printed_puts = killed_writer
    conn = sqlite3.connect(db)
    assert conn.execute("PRAGMA integrity_check").fetchone()[0] == "ok"
    conn.close()
    with SQLiteResultStore(db) as store:
        count = store.count()
        runs = sorted(key[-1] for key in store.done_keys())
        assert count >= MIN_ROWS
        assert count % BATCH == 0, "a partial batch was committed"
        assert runs == list(range(count)), "gaps or duplicates"
        # Every printed put is committed; the kill may fall between commit and print.
        assert count // BATCH in (printed_puts, printed_puts + 1)
        assert all(row["message"] == 'm, "q"\nline' for row in store.rows())


def test_rerun_resumes_the_same_plan_and_refuses_another(killed_writer: tuple[Path, int]) -> None:
    db, _ = killed_writer
    with SQLiteResultStore(db) as store:
        done = store.count()
        plan = store.init_plan("plan-a", '{"plan": "a"}')
        assert plan.plan_hash == "plan-a"
        total = done + 3 * BATCH
        todo = [result_row(run=run, seed=1) for run in range(total)]
        assert store.put(todo) == total - done
        assert store.count() == total
        with pytest.raises(PlanMismatch, match="use a new --db"):
            store.init_plan("plan-b", "{}")
