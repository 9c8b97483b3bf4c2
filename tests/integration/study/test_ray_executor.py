"""`study run --executor ray`: the same rows as the local executor with the same seed, on a
private local Ray and on a real two-node cluster on loopback that loses a worker mid-run;
the local executor never imports Ray.

Every Ray process these tests start carries a marker in its environment and is ended by its
process id afterwards (not with `ray stop`, which would end every Ray process of this user on
the machine, other sessions' included). Ray's files go to a short temporary folder and the
cluster's token lives in the environment, so nothing is written to /tmp/ray or ~/.ray.
"""

from __future__ import annotations

import contextlib
import json
import os
import secrets
import shutil
import signal
import socket
import sqlite3
import subprocess
import sys
import tempfile
import time
from collections.abc import Iterator
from pathlib import Path

import pytest

from tests.integration.study.test_resume import _rows, _same
from transfertwin.cli import main

pytest.importorskip("ray")

RAY = str(Path(sys.executable).with_name("ray"))
MARK = "TRANSFERTWIN_TEST_RAY"


def _study(db: Path, box_stl: Path, *extra: str) -> list[str]:
    """1 object x 4 states (θ = 0 only) x 2 runs = 8 experiments."""
    return [sys.executable, "-m", "transfertwin", "study", "run", "--db", str(db),
            "--objects", str(box_stl), "--units", "mm", "--theta-step", "360",
            "--runs", "2", "--seed", "5", *extra]  # fmt: skip


def _count(db: Path) -> int:
    try:
        with sqlite3.connect(f"file:{db}?mode=ro", uri=True, timeout=5) as con:
            return con.execute("SELECT COUNT(*) FROM results").fetchone()[0]
    except sqlite3.Error:
        return 0


def _environ(pid: int) -> dict[str, str]:
    try:
        raw = Path(f"/proc/{pid}/environ").read_bytes()
    except OSError:
        return {}
    return dict(e.split("=", 1) for e in raw.decode(errors="replace").split("\0") if "=" in e)


def _cmdline(pid: int) -> str:
    try:
        return Path(f"/proc/{pid}/cmdline").read_bytes().replace(b"\0", b" ").decode()
    except OSError:
        return ""


def _marked(mark: str) -> dict[int, dict[str, str]]:
    """Live processes whose environment carries `mark` → their environment."""
    found = {}
    for entry in Path("/proc").iterdir():
        if entry.name.isdigit() and int(entry.name) != os.getpid():
            env = _environ(int(entry.name))
            if env.get(MARK) == mark:
                found[int(entry.name)] = env
    return found


def _stats() -> dict[int, tuple[int, int]]:
    """Live process id → (parent id, start time); zombies left out."""
    stats = {}
    for entry in Path("/proc").iterdir():
        if entry.name.isdigit():
            try:
                fields = (entry / "stat").read_text().rsplit(")", 1)[1].split()
            except OSError:
                continue
            if fields[0] != "Z":
                stats[int(entry.name)] = (int(fields[1]), int(fields[19]))
    return stats


def _ours(mark: str) -> set[tuple[int, int]]:
    """(id, start time) of the processes carrying `mark` and of their descendants (Ray's
    agents and workers write their title over their environment, so only their parent
    tells where they belong)."""
    stats = _stats()
    ours = set(_marked(mark)) & set(stats)
    grew = True
    while grew:
        new = {pid for pid, (ppid, _) in stats.items() if ppid in ours} - ours
        ours |= new
        grew = bool(new)
    return {(pid, stats[pid][1]) for pid in ours}


def _end(mark: str) -> None:
    """SIGTERM, then SIGKILL, every process carrying `mark` and its descendants, by id (and
    start time, so a reused id is never hit). The tree is read before anything is killed:
    a child whose parent died belongs to init."""
    targets = _ours(mark)

    def alive() -> set[tuple[int, int]]:
        stats = _stats()
        return {(pid, t) for pid, t in targets if stats.get(pid, (0, -1))[1] == t}

    for sig in (signal.SIGTERM, signal.SIGKILL):
        targets |= _ours(mark)
        for pid, _ in alive():
            with contextlib.suppress(ProcessLookupError):
                os.kill(pid, sig)
        deadline = time.monotonic() + 10
        while alive() and time.monotonic() < deadline:
            time.sleep(0.2)
            targets |= _ours(mark)
    assert not alive(), "Ray processes outlived the test"


@contextlib.contextmanager
def _ray_env() -> Iterator[dict[str, str]]:
    """An environment for Ray processes: marker, private temp dir, token in the environment."""
    mark = secrets.token_hex(6)
    tmp = tempfile.mkdtemp(prefix="ttray", dir="/tmp")  # short: Ray's socket paths are long
    env = {**os.environ, MARK: mark, "RAY_TMPDIR": tmp, "RAY_AUTH_MODE": "token",
           "RAY_AUTH_TOKEN": secrets.token_hex(16), "RAY_USAGE_STATS_ENABLED": "0"}  # fmt: skip
    try:
        yield env
    finally:
        _end(mark)
        shutil.rmtree(tmp, ignore_errors=True)


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def test_local_executor_does_not_import_ray(tmp_path, box_stl):
    code = (
        "import sys\n"
        "import transfertwin.cli\n"
        "assert 'ray' not in sys.modules, 'import transfertwin.cli imported ray'\n"
        f"rc = transfertwin.cli.main({_study(tmp_path / 'l.sqlite', box_stl)[3:]!r}"
        " + ['--runs', '1', '--workers', '1'])\n"
        "assert rc == 0, rc\n"
        "assert 'ray' not in sys.modules, 'a local study run imported ray'\n"
    )
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          timeout=300)  # fmt: skip
    assert done.returncode == 0, done.stderr
    assert _count(tmp_path / "l.sqlite") == 4


def test_missing_ray_is_one_line_exit_2_and_no_db(tmp_path, box_stl):
    db = tmp_path / "r.sqlite"
    code = (
        "import sys\n"
        "sys.modules['ray'] = None  # as if Ray were not installed\n"
        "from transfertwin.cli import main\n"
        f"sys.exit(main({_study(db, box_stl)[3:]!r} + ['--executor', 'ray']))\n"
    )
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          timeout=120)  # fmt: skip
    assert done.returncode == 2
    assert done.stderr.strip().splitlines() == [
        "transfertwin: error: --executor ray needs Ray: pip install 'ray>=2.9' "
        "(or 'transfertwin[ray]')"
    ]
    assert not db.exists()


def test_local_ray_gives_the_rows_of_the_local_executor(tmp_path, box_stl):
    local, ray_db = tmp_path / "local.sqlite", tmp_path / "ray.sqlite"
    with _ray_env() as env:
        done = subprocess.run(_study(ray_db, box_stl, "--executor", "ray", "--workers", "2",
                                     "--chunk-size", "3"),
                              capture_output=True, text=True, env=env, timeout=300)  # fmt: skip
        assert done.returncode == 0, done.stderr
        assert "Ray (local Ray, 2 CPUs, 3 per task)" in done.stderr.replace("\n", " ")
    assert main([*_study(local, box_stl, "--workers", "1")[3:]]) == 0  # in process: no Ray
    assert len(_rows(ray_db)) == 8
    assert _same(_rows(ray_db), _rows(local))


@pytest.mark.slow
def test_calibration_on_local_ray_equals_local(tmp_path):
    cal = [sys.executable, "-m", "transfertwin", "calibrate", "run", "--limit", "6",
           "--runs", "2", "--seed", "3"]  # fmt: skip
    with _ray_env() as env:
        on_ray = subprocess.run([*cal, "--out", str(tmp_path / "ray"), "--executor", "ray",
                                 "--workers", "2", "--chunk-size", "2"],
                                capture_output=True, text=True, env=env, timeout=300)  # fmt: skip
        assert on_ray.returncode == 0, on_ray.stderr
    local = subprocess.run([*cal, "--out", str(tmp_path / "local"), "--workers", "1"],
                           capture_output=True, text=True, timeout=300)  # fmt: skip
    assert local.returncode == 0, local.stderr
    metrics = [json.loads((tmp_path / d / "metrics.json").read_text()) for d in ("ray", "local")]
    assert metrics[0]["runs"] == metrics[1]["runs"] and len(metrics[0]["runs"]) == 2


@pytest.mark.slow
def test_cluster_on_loopback_survives_a_killed_worker(tmp_path, box_stl):
    local, ray_db = tmp_path / "local.sqlite", tmp_path / "ray.sqlite"
    port = _free_port()
    common = ["--num-cpus=1", "--object-store-memory=100000000", "--disable-usage-stats"]
    with _ray_env() as env:
        head = [RAY, "start", "--head", f"--port={port}", "--include-dashboard=false", *common]
        subprocess.run(head, env=env, check=True, capture_output=True, timeout=180)
        node_env = {**env, "TRANSFERTWIN_TEST_NODE": "worker"}
        node = [RAY, "start", f"--address=127.0.0.1:{port}", *common]
        subprocess.run(node, env=node_env, check=True, capture_output=True, timeout=180)
        study = _study(ray_db, box_stl, "--executor", "ray", "--address", f"127.0.0.1:{port}",
                       "--chunk-size", "1")  # fmt: skip
        proc = subprocess.Popen(study, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE,
                                text=True, env=env)  # fmt: skip
        try:
            node_raylets = {
                pid
                for pid, penv in _marked(env[MARK]).items()
                if penv.get("TRANSFERTWIN_TEST_NODE") and "raylet" in _cmdline(pid)
            }
            assert len(node_raylets) == 1, node_raylets  # fmt: skip
            victim, deadline = None, time.monotonic() + 240
            while victim is None and proc.poll() is None and time.monotonic() < deadline:
                # a Ray worker process of the worker node, running a chunk right now
                running = [
                    pid
                    for pid, (ppid, _) in _stats().items()
                    if ppid in node_raylets and _cmdline(pid).startswith("ray::run_chunk")
                ]
                victim = running[0] if running else None  # fmt: skip
                time.sleep(0.05)
            assert victim is not None, "no chunk ran on the worker node"
            stored_at_kill = _count(ray_db)
            os.kill(victim, signal.SIGKILL)
            assert proc.poll() is None and stored_at_kill < 8, "the study was not mid-run"
            _, err = proc.communicate(timeout=300)
        finally:
            if proc.poll() is None:
                proc.kill()
                proc.wait()
        assert proc.returncode == 0, err
    ref = subprocess.run(_study(local, box_stl, "--workers", "1"), capture_output=True,
                         text=True, timeout=300)  # fmt: skip
    assert ref.returncode == 0, ref.stderr
    rows = _rows(ray_db)
    keys = [(r["object_id"], r["face"], r["conveyor"], r["theta_deg"], r["run"]) for r in rows]
    assert len(keys) == len(set(keys)) == 8
    assert _same(rows, _rows(local))
