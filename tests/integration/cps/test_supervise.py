"""`cps supervise` beside a detached floor (slow: a floor of 8 processes, ~40 s): a unit
killed with -9 is restarted from its bundle and rejoins as a new instance; a unit stopped as
asked stays down; `cps down` ends the supervisor without a restart."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time

import pytest

from tests.integration.cps._cli import plant_floor, tt, two_module_floor

pytestmark = pytest.mark.slow

FLOOR = two_module_floor("supervised", {"o1": "TU_A"})


def _online(wd) -> dict[str, dict]:
    from transfertwin.cli._cps_floor import floor_status

    return {a["id"]: a for a in floor_status(wd)["assets"] if a["online"]}


def _until(check, timeout_s: float, what: str):
    t0 = time.monotonic()
    while time.monotonic() - t0 < timeout_s:
        got = check()
        if got:
            return got
        time.sleep(0.3)
    raise AssertionError(f"not within {timeout_s} s: {what}")


def test_a_unit_killed_with_minus_9_is_restarted_and_one_stopped_as_asked_is_not(
        tmp_path_factory):  # fmt: skip
    from transfertwin.cps import asset_pids

    floor = plant_floor(tmp_path_factory.mktemp("supervise"), FLOOR)
    wd = next(floor)
    sup = subprocess.Popen([sys.executable, "-m", "transfertwin", "cps", "supervise",
                            "--workdir", str(wd), "--window", "60"],
                           stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)  # fmt: skip
    try:
        _until(lambda: set(_online(wd)) >= {"TU_A", "TU_B", "TM_1"}, 30, "the floor online")
        before = _online(wd)["TU_B"]
        os.kill(asset_pids(wd)["TU_B"], signal.SIGKILL)
        after = _until(lambda: (a := _online(wd).get("TU_B")) and a["pid"] != before["pid"]
                       and a, 60, "TU_B restarted and online")  # fmt: skip
        assert after["pid"] == asset_pids(wd)["TU_B"]
        down = tt("cps", "down", "--workdir", str(wd), "--asset", "TU_A")  # stopped as asked
        assert down.returncode == 0, down.stderr
        _until(lambda: "TU_A" not in asset_pids(wd), 30, "TU_A stopped")
        time.sleep(3)  # three looks of the supervisor
        assert "TU_A" not in asset_pids(wd)
    finally:
        for _ in floor:  # cps down, checked
            pass
    out, err = sup.communicate(timeout=30)
    assert sup.returncode == 0, err
    lines = out.splitlines()
    restarts = [line for line in lines if "died" in line]
    assert len(restarts) == 1 and "TU_B died (pid " in restarts[0], out
    assert "restarted as pid" in restarts[0]
    assert lines[-1] == "floor down: no asset process of it runs any more"
