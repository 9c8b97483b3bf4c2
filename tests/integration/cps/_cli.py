"""The CLI as a user runs it: `transfertwin ...` subprocesses, and a running `cps up`."""

from __future__ import annotations

import signal
import subprocess
import sys
import time
from pathlib import Path

__all__ = ["PLANT_SEED", "RunningCps", "tt"]

#: Plant seed of the test run's shared CPS (conftest.py: `plant_cps`).
PLANT_SEED = 913


def tt(*args: str, timeout: float = 300, env: dict | None = None) -> subprocess.CompletedProcess:
    """`transfertwin ARGS` in a fresh interpreter."""
    return subprocess.run([sys.executable, "-m", "transfertwin", *args], capture_output=True,
                          text=True, timeout=timeout, env=env)  # fmt: skip


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
             "--time-scale", "0", *extra], stdout=subprocess.PIPE, stderr=self._err, text=True,
        )  # fmt: skip
        self.first_line: str | None = None

    def wait_up(self) -> RunningCps:
        if self.first_line is None:
            self.first_line = self.proc.stdout.readline()  # blocks until the CPS is up
        return self

    @property
    def running(self) -> bool:
        return self.proc.poll() is None

    def order(self, source: str, target: str, obj: str, *extra: str):
        return tt("cps", "order", "--workdir", str(self.wd), "--from", source, "--to", target,
                  "--object", obj, *extra)  # fmt: skip

    def stop(self) -> tuple[int, str, float]:
        """SIGTERM; (exit code, the rest of stdout, seconds to exit)."""
        self.proc.send_signal(signal.SIGTERM)
        t0 = time.monotonic()
        out, _ = self.proc.communicate(timeout=120)
        self._err.close()
        return self.proc.returncode, out, time.monotonic() - t0
