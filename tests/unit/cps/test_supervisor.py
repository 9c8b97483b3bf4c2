"""`cps.Supervisor`: an asset whose pid file outlives its process died unasked and is
restarted from its bundle, at most `max_restarts` times within the window; one stopped as
asked (no pid file) or on standby is never started."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

from transfertwin.cps import Supervisor


def _dead_pid() -> int:
    proc = subprocess.Popen([sys.executable, "-c", "pass"])
    proc.wait()
    return proc.pid


class _Starts:
    """Starts a real process per restart (it sleeps; it writes no pid file of its own)."""

    def __init__(self) -> None:
        self.calls: list[tuple[Path, Path]] = []
        self.procs: list[subprocess.Popen] = []

    def __call__(self, config: Path, log: Path) -> subprocess.Popen:
        self.calls.append((config, log))
        self.procs.append(subprocess.Popen(["sleep", "60"]))
        return self.procs[-1]


@pytest.fixture
def starts():
    s = _Starts()
    yield s
    for p in s.procs:
        p.kill()
        p.wait()


def _pid_file(wd: Path, aid: str, pid: int) -> None:
    state = wd / "assets" / aid / "state"
    state.mkdir(parents=True, exist_ok=True)
    (state / "pid").write_text(f"{pid}\n")


def test_an_asset_that_died_is_restarted_until_it_dies_too_often(tmp_path, starts):
    now = [0.0]
    sup = Supervisor(tmp_path, max_restarts=2, window_s=60.0, clock=lambda: now[0],
                     start=starts)  # fmt: skip
    _pid_file(tmp_path, "TU_B", _dead_pid())  # killed with -9: its pid file stayed
    (tmp_path / "assets" / "TU_A" / "state").mkdir(parents=True)  # stopped as asked: no file
    (first,) = sup.tick()
    assert first.startswith("TU_B died (pid ")
    assert first.endswith(f"restarted as pid {starts.procs[0].pid}")
    assert starts.calls == [(tmp_path / "assets" / "TU_B" / "asset.toml",
                             tmp_path / "logs" / "TU_B.log")]  # fmt: skip
    assert sup.tick() == []  # starting: the old pid file is not a second death
    _pid_file(tmp_path, "TU_B", starts.procs[0].pid)  # it came up and wrote its own
    assert sup.tick() == [] and sup.died() == {}
    starts.procs[0].kill()
    starts.procs[0].wait()
    now[0] = 10.0
    assert sup.tick()[0].startswith("TU_B died")  # the second restart within the window
    _pid_file(tmp_path, "TU_B", starts.procs[1].pid)
    starts.procs[1].kill()
    starts.procs[1].wait()
    now[0] = 20.0
    (gave_up,) = sup.tick()
    assert gave_up.startswith("TU_B died 3 times within 60 s: left down")
    assert sup.given_up == {"TU_B"} and len(starts.calls) == 2
    assert sup.tick() == []  # left down, said once


def test_restarts_older_than_the_window_do_not_count(tmp_path, starts):
    now = [0.0]
    sup = Supervisor(tmp_path, max_restarts=1, window_s=30.0, clock=lambda: now[0],
                     start=starts)  # fmt: skip
    for t in (0.0, 31.0, 62.0):  # one death every 31 s: each restarted
        now[0] = t
        if starts.procs:
            _pid_file(tmp_path, "KG", starts.procs[-1].pid)
            starts.procs[-1].kill()
            starts.procs[-1].wait()
        else:
            _pid_file(tmp_path, "KG", _dead_pid())
        assert sup.tick()[0].startswith("KG died"), t
    assert len(starts.calls) == 3 and not sup.given_up


def test_a_running_asset_is_left_alone(tmp_path, starts):
    sup = Supervisor(tmp_path, start=starts)
    alive = subprocess.Popen(["sleep", "60"])
    try:
        _pid_file(tmp_path, "TM_1", alive.pid)
        assert sup.died() == {} and sup.tick() == [] and starts.calls == []
    finally:
        alive.kill()
        alive.wait()
    with pytest.raises(ValueError):
        Supervisor(tmp_path, max_restarts=0)
