"""A study killed with SIGKILL resumes to exactly the planned rows, none twice, and equals an
uninterrupted run with the same seed."""

from __future__ import annotations

import math
import os
import signal
import sqlite3
import subprocess
import sys
import time

from transfertwin.store import SQLiteResultStore


def _cmd(db, box_stl, workers: int, theta_step: int = 30, *extra: str) -> list[str]:
    return [sys.executable, "-m", "transfertwin", "study", "run", "--db", str(db),
            "--objects", str(box_stl), "--units", "mm", "--theta-step", str(theta_step),
            "--runs", "2", "--seed", "11", "--workers", str(workers), *extra]  # fmt: skip


def _count(db) -> int:
    try:
        with sqlite3.connect(f"file:{db}?mode=ro", uri=True, timeout=5) as con:
            return con.execute("SELECT COUNT(*) FROM results").fetchone()[0]
    except sqlite3.Error:
        return 0


def _rows(db) -> list[dict]:
    with SQLiteResultStore(db, create=False) as store:
        rows = list(store.rows())
    for r in rows:
        r.pop("finished_utc")
    return rows


def _same(a: list[dict], b: list[dict]) -> bool:
    def norm(v):
        return "nan" if isinstance(v, float) and math.isnan(v) else v

    return [{k: norm(v) for k, v in r.items()} for r in a] == [
        {k: norm(v) for k, v in r.items()} for r in b
    ]


def test_sigkill_then_resume_equals_uninterrupted_run(tmp_path, box_stl):
    killed, clean = tmp_path / "killed.sqlite", tmp_path / "clean.sqlite"
    env = {**os.environ, "PYTHONUNBUFFERED": "1"}
    proc = subprocess.Popen(_cmd(killed, box_stl, 2), stdout=subprocess.DEVNULL,
                            stderr=subprocess.DEVNULL, env=env, start_new_session=True)  # fmt: skip
    deadline = time.monotonic() + 240
    while _count(killed) < 10 and time.monotonic() < deadline and proc.poll() is None:
        time.sleep(0.05)  # polling the db, not waiting a fixed time
    assert proc.poll() is None, "study finished before it could be killed"
    os.killpg(proc.pid, signal.SIGKILL)  # the runner and its workers die at once
    proc.wait(timeout=30)
    partial = _count(killed)
    assert 10 <= partial < 56

    for db, workers in ((killed, 2), (clean, 1)):
        done = subprocess.run(_cmd(db, box_stl, workers), capture_output=True, timeout=300)
        assert done.returncode == 0, done.stderr
    resumed, reference = _rows(killed), _rows(clean)
    keys = [(r["object_id"], r["face"], r["conveyor"], r["theta_deg"], r["run"]) for r in resumed]
    assert len(keys) == len(set(keys)) == 28 * 2
    assert _same(resumed, reference)


def test_a_different_plan_on_the_same_db_is_refused(tmp_path, box_stl):
    db = tmp_path / "s.sqlite"
    first = _cmd(db, box_stl, 1, 30, "--max-experiments", "2")
    assert subprocess.run(first, capture_output=True, timeout=300).returncode == 0
    other = subprocess.run(_cmd(db, box_stl, 1, 90), capture_output=True, text=True,
                           timeout=300)  # fmt: skip
    assert other.returncode == 2
    assert "different study plan" in other.stderr
    assert len(other.stderr.strip().splitlines()) == 1


def _children(pid: int) -> set[int]:
    kids: set[int] = set()
    for task in os.listdir(f"/proc/{pid}/task"):
        with open(f"/proc/{pid}/task/{task}/children") as fh:
            kids |= {int(p) for p in fh.read().split()}
    return kids


def _alive(pid: int) -> bool:
    try:
        with open(f"/proc/{pid}/stat") as fh:
            return fh.read().split(")")[-1].split()[0] != "Z"
    except FileNotFoundError:
        return False


def test_workers_exit_when_the_runner_is_killed(tmp_path, box_stl):
    db = tmp_path / "orphans.sqlite"
    proc = subprocess.Popen(_cmd(db, box_stl, 2), stdout=subprocess.DEVNULL,
                            stderr=subprocess.DEVNULL, start_new_session=True)  # fmt: skip
    try:
        deadline = time.monotonic() + 240
        while _count(db) < 2 and time.monotonic() < deadline and proc.poll() is None:
            time.sleep(0.05)
        assert proc.poll() is None, "study finished before it could be killed"
        workers = _children(proc.pid)
        assert len(workers) >= 2  # two pool workers (and the resource tracker)
        os.kill(proc.pid, signal.SIGKILL)  # the runner alone: no clean-up runs
        proc.wait(timeout=30)
        deadline = time.monotonic() + 20
        while any(_alive(w) for w in workers) and time.monotonic() < deadline:
            time.sleep(0.1)
        assert not [w for w in workers if _alive(w)], "orphaned workers still running"
    finally:
        os.killpg(proc.pid, signal.SIGKILL) if proc.poll() is None else None
