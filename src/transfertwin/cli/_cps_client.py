"""What every `transfertwin cps` client command shares: the work folder and its cps.json,
the client credentials, one call on an asset's server, and plain-text tables.

The `cps` command modules (`_cps`, `_cps_floor`, `_cps_ops`, `_cps_study`) import these
helpers from here and not from each other, so the commands form no circle.
"""

from __future__ import annotations

import asyncio
import json
from collections.abc import Awaitable, Callable
from pathlib import Path
from typing import TypeVar

from transfertwin._errors import InputError
from transfertwin.cli._paths import out_dir

__all__ = ["call_asset", "endpoint_of", "load_info", "run_client", "text_table", "workdir_of"]

T = TypeVar("T")


def workdir_of(path: str, must_exist: bool) -> Path:
    """The CPS work folder `path`; with `must_exist`, one with a running CPS (its cps.json)."""
    if not must_exist:
        return out_dir(path)
    wd = Path(path)
    if not (wd / "cps.json").is_file():
        raise InputError(f"{path}: the CPS is not running (no cps.json); start it with "
                         "'transfertwin cps up'")  # fmt: skip
    return wd


def load_info(wd: Path) -> tuple[dict, object]:
    """The floor's cps.json and the client credentials it names (None when insecure)."""
    from transfertwin.cps.opcua import load_credentials

    path = wd / "cps.json"
    if not path.is_file():
        raise InputError(f"{wd}: no floor there (no cps.json); start one with "
                         "'transfertwin cps up --floor FLOOR --workdir DIR'")  # fmt: skip
    info = json.loads(path.read_text())
    creds = None if info.get("insecure") else load_credentials(Path(info["credentials_file"]))
    return info, creds


def endpoint_of(info: dict, asset_id: str) -> str:
    """The OPC UA endpoint of `asset_id` in cps.json (InputError if there is none)."""
    for a in info["assets"]:
        if a["id"] == asset_id:
            return a["endpoint"]
    raise InputError(f"no asset {asset_id!r} in the CPS")


async def call_asset(info: dict, creds, aid: str, op: str, *args, timeout_s: float = 10.0):
    """Call method `op` of asset `aid` as an operator; its answer."""
    from transfertwin.cps.opcua import connect

    async with connect(endpoint_of(info, aid), aid, credentials=creds, role="operator",
                       cert_dir=Path(info["cert_dir"]), insecure=info["insecure"],
                       timeout_s=timeout_s) as s:  # fmt: skip
        return await s.call(op, *args)


def run_client(wd: Path, coro_fn: Callable[[], Awaitable[T]]) -> T:
    """Run a client coroutine; a CPS that does not answer is reported in one line."""
    from asyncua import ua

    try:
        return asyncio.run(coro_fn())
    except (TimeoutError, ConnectionError, OSError) as exc:
        raise InputError(
            f"{wd}: the CPS is not running or not answering "
            f"({type(exc).__name__}); start it with 'transfertwin cps up'"
        ) from None
    except ua.UaStatusCodeError as exc:
        if exc.code != ua.StatusCodes.BadCertificateUntrusted:
            raise
        raise InputError(
            f"{wd}: the CPS does not trust this client's certificate; trust it with "
            "'transfertwin cps trust CERT --workdir WORKDIR'"
        ) from None


def text_table(rows: list[dict], cols: tuple[str, ...]) -> str:
    """Plain columns, nothing truncated whatever the terminal width (the endpoint last)."""
    cells = [[str(r.get(c, "") or "") for c in cols] for r in rows]
    widths = [max([len(c), *(len(row[i]) for row in cells)]) for i, c in enumerate(cols)]
    lines = [cols, *cells]
    return "\n".join("  ".join(v.ljust(w) for v, w in zip(line, widths, strict=True)).rstrip()
                     for line in lines)  # fmt: skip
