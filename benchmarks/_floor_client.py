"""Shared client of the benchmarks that drive a running process floor (`cps up --detach`):
the command line in a subprocess and the TMS's operations over OPC UA.

Used by planning_latency.py, operations.py and cps_chaos.py (run as scripts from the
repository root, so `benchmarks/` is on `sys.path` as for `_engine.py` and `_stress.py`).
"""

from __future__ import annotations

import asyncio
import subprocess
import sys
from pathlib import Path


def tt(*args: str, timeout: float = 600) -> subprocess.CompletedProcess:
    """`python -m transfertwin ARGS` in this interpreter, output captured (timeout in s)."""
    return subprocess.run([sys.executable, "-m", "transfertwin", *args], capture_output=True,
                          text=True, timeout=timeout)  # fmt: skip


class Tms:
    """The floor's TMS in the workdir `wd`: `tms(op, *args)` calls one of its operations
    (20 s timeout) and returns its output."""

    def __init__(self, wd: Path) -> None:
        from transfertwin.cli._cps_client import load_info

        self.info, self.creds = load_info(wd)

    def __call__(self, op: str, *args):
        from transfertwin.cli._cps_client import call_asset

        return asyncio.run(call_asset(self.info, self.creds, "TMS", op, *args, timeout_s=20))
