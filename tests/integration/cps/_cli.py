"""The CLI as a user runs it: `transfertwin ...` in a process of its own (`tt`) or through
`transfertwin.cli.main` in this one (`run_main`, as tests/integration/cli/test_bad_input.py
does: the same exit code, stdout and stderr, without an interpreter start and the imports
of a CLI process, ~1–2 s of CPU each), a running `cps up`, and process floors started
ahead of their tests (`early_floor`)."""

from __future__ import annotations

import logging
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

__all__ = ["PLANT_SEED", "EarlyFloor", "RunningCps", "call_tms", "early_floor", "early_floors",
           "plant_floor", "run_main", "small_study", "tt", "two_module_floor"]

#: Plant seed of the test run's shared CPS (conftest.py: `plant_cps`).
PLANT_SEED = 913


def two_module_floor(name: str, objects: dict[str, str]) -> str:
    """A floor file: stations A and B (TU_A, TU_B), TM_1 running and TM_2 on standby, the
    knowledge graph and the TMS, and `objects` (id -> the unit it lies on)."""
    head = f"""
name = "{name}"
size_m = [12.0, 8.0]
logical = ["KG", "TMS"]

[[station]]
name = "A"
x_m = 2.6
y_m = 6.6
yaw_deg = 90.0
mount = "left"

[[station]]
name = "B"
x_m = 7.6
y_m = 6.6
yaw_deg = 90.0
mount = "right"

[[module]]
id = "TM_1"
x_m = 6.0
y_m = 5.2

[[module]]
id = "TM_2"
x_m = 6.0
y_m = 3.0
standby = true
"""
    return head + "".join(f'\n[[object]]\nid = "{o}"\nat = "{at}"\n' for o, at in objects.items())


def call_tms(wd: Path, op: str, *args):
    """Call `op` of the TMS of the floor in `wd` as its operator (20 s timeout)."""
    import asyncio

    from transfertwin.cli._cps_client import call_asset, load_info

    info, creds = load_info(wd)
    return asyncio.run(call_asset(info, creds, "TMS", op, *args, timeout_s=20))


def plant_floor(base: Path, floor_text: str, *flags: str):
    """A detached floor of `floor_text` on the emulated plant of seed 7 (`flags` added to
    `cps up`), as a generator for a module-scoped fixture: yields the work folder, then takes
    the floor down and checks that every asset stopped over OPC UA (none killed)."""
    (base / "floor.toml").write_text(floor_text)
    wd = base / "w"
    up = tt("cps", "up", "--floor", str(base / "floor.toml"), "--workdir", str(wd), "--detach",
            "--time-scale", "0", "--plant-seed", "7", "--lease", "10", *flags,
            "--start-timeout", "150", timeout=200)  # fmt: skip
    assert up.returncode == 0, up.stderr
    try:
        yield wd
    finally:
        down = tt("cps", "down", "--workdir", str(wd))
    assert down.returncode == 0 and "killed" not in down.stdout, down.stdout + down.stderr


def small_study(path: Path, obj: str) -> None:
    """A real study store of `obj`: the 12 states at θ = 0, ±90 and 180, one run each."""
    from transfertwin.cps.apps import docking_model
    from transfertwin.store import SQLiteResultStore
    from transfertwin.study.experiment import StudyPlan, run_study

    store = SQLiteResultStore(path)
    try:
        run_study(StudyPlan((obj,), 90, 1, 0, docking_model()), store, workers=1)
    finally:
        store.close()


def tt(*args: str, timeout: float = 300, env: dict | None = None) -> subprocess.CompletedProcess:
    """`transfertwin ARGS` in a fresh interpreter."""
    return subprocess.run([sys.executable, "-m", "transfertwin", *args], capture_output=True,
                          text=True, timeout=timeout, env=env)  # fmt: skip


def run_main(capfd: pytest.CaptureFixture[str], *args: str) -> subprocess.CompletedProcess:
    """`transfertwin ARGS` through `main` in this process: exit code, stdout, stderr."""
    from transfertwin.cli import main

    capfd.readouterr()  # what came before is not this command's
    root, ua = logging.getLogger(), logging.getLogger("asyncua")
    levels = root.level, ua.level
    try:
        code = main(list(args))
    finally:  # main's stderr handler and levels are this command's only
        for h in [h for h in root.handlers if h.get_name() == "transfertwin-cli"]:
            root.removeHandler(h)
        root.setLevel(levels[0])
        ua.setLevel(levels[1])
    out, err = capfd.readouterr()
    return subprocess.CompletedProcess(["transfertwin", *args], code, out, err)


class RunningCps:
    """A `cps up` subprocess; stderr goes to a file the tests read.

    Starting returns at once; `wait_up` blocks until the CPS reports it is up (its first
    line on stdout), so a test run can let it come up while other tests run.
    """

    def __init__(self, wd: Path, *extra: str) -> None:
        self.wd = wd
        wd.parent.mkdir(parents=True, exist_ok=True)
        self.stderr_path = wd.parent / "up.stderr"
        self._err = self.stderr_path.open("w")
        self.proc = subprocess.Popen(
            [sys.executable, "-m", "transfertwin", "cps", "up", "--workdir", str(wd),
             "--time-scale", "0", "--policy", "nearest-idle", *extra],
            stdout=subprocess.PIPE, stderr=self._err, text=True,
        )  # fmt: skip
        self.first_line: str | None = None

    def wait_up(self) -> RunningCps:
        if self.first_line is None:
            self.first_line = self.proc.stdout.readline()  # blocks until the CPS is up
        return self

    @property
    def running(self) -> bool:
        return self.proc.poll() is None

    def order_args(self, source: str, target: str, obj: str) -> tuple[str, ...]:
        return ("cps", "order", "--workdir", str(self.wd), "--from", source, "--to", target,
                "--object", obj)  # fmt: skip

    def order(self, source: str, target: str, obj: str):
        """`cps order` in a process of its own."""
        return tt(*self.order_args(source, target, obj))

    def stop(self) -> tuple[int, str, float]:
        """SIGTERM; (exit code, the rest of stdout, seconds to exit)."""
        self.proc.send_signal(signal.SIGTERM)
        t0 = time.monotonic()
        out, _ = self.proc.communicate(timeout=120)
        self._err.close()
        return self.proc.returncode, out, time.monotonic() - t0


class EarlyFloor:
    """`cps up --floor FLOOR --workdir W --detach ARGS` in a process of its own, started at
    once; `result` waits for it (the floor comes up while the tests before its own run)."""

    def __init__(self, base: Path, floor_text: str, args: tuple[str, ...]) -> None:
        (base / "floor.toml").write_text(floor_text)
        self.wd = base / "w"
        self.proc = subprocess.Popen(
            [sys.executable, "-m", "transfertwin", "cps", "up", "--floor", str(base / "floor.toml"),
             "--workdir", str(self.wd), "--detach", "--policy", "nearest-idle", *args],
            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)  # fmt: skip
        self._result: subprocess.CompletedProcess | None = None
        self.down = False

    def result(self, timeout_s: float = 200) -> subprocess.CompletedProcess:
        """What `cps up` exited with (stdout, stderr), once it has."""
        if self._result is None:
            out, err = self.proc.communicate(timeout=timeout_s)
            self._result = subprocess.CompletedProcess(self.proc.args, self.proc.returncode,
                                                       out, err)  # fmt: skip
        return self._result

    def stop(self) -> subprocess.CompletedProcess:
        """`cps down` (once)."""
        self.down = True
        return subprocess.run([sys.executable, "-m", "transfertwin", "cps", "down", "--workdir",
                               str(self.wd)], capture_output=True, text=True, timeout=120)


_FLOORS: dict[str, EarlyFloor] = {}


def early_floors() -> list[EarlyFloor]:
    """The process floors started in this run."""
    return list(_FLOORS.values())


def early_floor(factory: pytest.TempPathFactory, key: str, floor_text: str,
                args: tuple[str, ...]) -> EarlyFloor:  # fmt: skip
    """The process floor `key` of this run, started now if it was not started ahead (a test
    module names it in ``EARLY_FLOOR = (key, floor file text, cps up arguments)``)."""
    if key not in _FLOORS:
        _FLOORS[key] = EarlyFloor(factory.mktemp(key), floor_text, args)
    return _FLOORS[key]
