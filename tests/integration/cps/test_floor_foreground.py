"""`cps up` in the foreground ends with its floor: taken down from another shell with
`cps down`, it says so and exits 0 instead of waiting for a signal that will not come.
Slow (real time: the demo floor's 14 processes come up, ~20-40 s)."""

from __future__ import annotations

import subprocess
import time

import pytest

from tests.integration.cps._cli import RunningCps, tt


@pytest.mark.slow
def test_cps_up_in_the_foreground_ends_when_the_floor_is_taken_down(tmp_path) -> None:
    cps = RunningCps(tmp_path / "cps").wait_up()
    try:
        assert cps.first_line.startswith("floor demo up: 14 asset processes"), cps.first_line
        assert cps.running
        down = tt("cps", "down", "--workdir", str(cps.wd))
        assert down.returncode == 0, down.stderr
        t0 = time.monotonic()
        out, _ = cps.proc.communicate(timeout=60)
        took = time.monotonic() - t0
    except (AssertionError, subprocess.TimeoutExpired):
        cps.stop()
        raise
    assert cps.proc.returncode == 0
    assert out.strip().splitlines()[-1] == "floor down: no asset process of it runs any more"
    assert took < 20, took  # noticed within a few seconds of the last asset leaving
