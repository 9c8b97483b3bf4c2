"""Restarting the asset processes of a floor that died unasked (docs/architecture.md,
"Deployment").

An asset process keeps its pid in ``W/assets/<id>/state/pid`` while it runs and removes the
file when it stops as asked (SIGTERM, ``Shutdown`` over OPC UA, `cps down`, which also
removes the file of a process it has to kill). A pid file whose process is gone therefore
names a process that died unasked: killed with -9, crashed, or taken by the kernel's OOM
killer. `Supervisor` restarts such an asset from its bundle, as ``cps asset`` by hand does
(its state, leases and journals are on disk: it rejoins as a new instance), at most
`max_restarts` times within `window_s`; an asset that dies more often is left down and
reported (a crash loop needs a person, not more restarts). Assets on standby and assets
stopped as asked are never started.
"""

from __future__ import annotations

import subprocess
import time
from collections import deque
from collections.abc import Callable
from pathlib import Path

from transfertwin.cps._launcher import BUNDLE_CONFIG, pid_alive, start_asset

__all__ = ["Supervisor"]


class Supervisor:
    """Restarts the floor's asset processes that died unasked (see the module docstring).

    Args:
        workdir: The floor's work folder (``cps up --workdir``).
        max_restarts: Restarts of one asset allowed within `window_s`.
        window_s: The window (s) over which restarts are counted.
        clock: Monotonic seconds (a test's own clock).
        start: Starts an asset from its bundle's config, logging to a file (`start_asset`).
    """

    def __init__(
        self, workdir: Path, max_restarts: int = 5, window_s: float = 300.0,
        clock: Callable[[], float] = time.monotonic,
        start: Callable[[Path, Path], subprocess.Popen] = start_asset,
    ) -> None:  # fmt: skip
        if max_restarts < 1 or not window_s > 0:
            raise ValueError("max_restarts must be >= 1 and window_s > 0")
        self.workdir = Path(workdir)
        self.max_restarts = max_restarts
        self.window_s = window_s
        self._clock = clock
        self._start = start
        self._restarts: dict[str, deque[float]] = {}
        self._starting: dict[str, subprocess.Popen] = {}
        self.given_up: set[str] = set()

    def died(self) -> dict[str, int]:
        """Asset id -> pid of each asset whose pid file names a process that is gone (not one
        restarted here that has not written its own pid file yet)."""
        out = {}
        for f in sorted((self.workdir / "assets").glob("*/state/pid")):
            aid = f.parent.parent.name
            try:
                pid = int(f.read_text())
            except (ValueError, OSError):  # being written, or removed just now
                continue
            starting = self._starting.get(aid)
            if pid_alive(pid) or (starting is not None and starting.poll() is None
                                  and starting.pid != pid):  # fmt: skip
                continue
            out[aid] = pid
        return out

    def tick(self) -> list[str]:
        """Restart what died since the last tick; one line per asset restarted or given up."""
        lines = []
        now = self._clock()
        for aid, pid in self.died().items():
            if aid in self.given_up:
                continue
            recent = self._restarts.setdefault(aid, deque())
            while recent and now - recent[0] > self.window_s:
                recent.popleft()
            log = self.workdir / "logs" / f"{aid}.log"
            if len(recent) >= self.max_restarts:
                self.given_up.add(aid)
                lines.append(f"{aid} died {len(recent) + 1} times within {self.window_s:g} s: "
                             f"left down (see {log}; start it with 'transfertwin cps asset "
                             f"{self.workdir / 'assets' / aid}')")  # fmt: skip
                continue
            log.parent.mkdir(parents=True, exist_ok=True)
            proc = self._start(self.workdir / "assets" / aid / BUNDLE_CONFIG, log)
            self._starting[aid] = proc
            recent.append(now)
            lines.append(f"{aid} died (pid {pid} gone, not stopped as asked): restarted as "
                         f"pid {proc.pid}")  # fmt: skip
        return lines
