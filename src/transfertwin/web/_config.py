"""Settings of the web console and the checks made before anything starts listening."""

from __future__ import annotations

import ipaddress
import secrets
from dataclasses import dataclass, field
from pathlib import Path

from transfertwin._errors import InputError
from transfertwin.web._calibration import check_calibration_dir

__all__ = ["WebConfig", "is_loopback"]


def is_loopback(host: str) -> bool:
    """Whether `host` names a loopback interface ('localhost', 127.0.0.0/8, ::1)."""
    if host == "localhost":
        return True
    try:
        return ipaddress.ip_address(host).is_loopback
    except ValueError:
        return False  # a host name other than localhost: treat as reachable from outside


@dataclass(frozen=True)
class WebConfig:
    """What the console serves and how it is protected.

    Attributes:
        cps: Work folder of a running `transfertwin cps up` (holds cps.json), or None.
        dbs: Study result stores (SQLite) whose progress and results are shown.
        calibrations: Output folders of `calibrate run` / `calibrate evaluate` whose
            real-vs-virtual comparison is shown.
        host: Interface to bind; loopback unless a token is given.
        port: TCP port.
        token: Secret every write action (and, off loopback, every request) must carry.
            None on loopback: a random one is made (printed with the console's URL).
        live_period_s: How often live values are read over OPC UA and pushed.
    """

    cps: Path | None = None
    dbs: tuple[Path, ...] = ()
    calibrations: tuple[Path, ...] = ()
    host: str = "127.0.0.1"
    port: int = 8765
    token: str | None = None
    live_period_s: float = 0.5
    session_token: str = field(default="", repr=False)

    def __post_init__(self) -> None:
        if not is_loopback(self.host) and not self.token:
            raise InputError(
                f"--host {self.host} is not loopback: give --token so that the console is "
                "not open to the network"
            )
        if self.token is not None and len(self.token) < 8:
            raise InputError("--token must be at least 8 characters")
        if not 0 <= self.port <= 65535:
            raise InputError(f"--port must be in 0..65535, got {self.port}")
        if not 0.05 <= self.live_period_s <= 1.0:
            raise InputError(f"the live period must be in 0.05..1 s, got {self.live_period_s}")
        if self.cps is not None and not (self.cps / "cps.json").is_file():
            raise InputError(
                f"--cps {self.cps}: the CPS is not running (no cps.json); start it with "
                "'transfertwin cps up'"
            )
        for db in self.dbs:
            if not db.is_file():
                raise InputError(f"--db {db}: no such file")
        names = [db.name for db in self.dbs]
        if len(set(names)) != len(names):
            raise InputError("--db: two stores with the same file name")
        for folder in self.calibrations:
            check_calibration_dir(folder)
        names = [folder.name for folder in self.calibrations]
        if len(set(names)) != len(names):
            raise InputError("--calibration: two folders with the same name")
        if not self.session_token:
            object.__setattr__(self, "session_token", self.token or secrets.token_urlsafe(18))

    @property
    def reads_need_token(self) -> bool:
        """Off loopback every request needs the token, on loopback only write actions."""
        return not is_loopback(self.host)
