"""Stopping asyncio tasks that may swallow their cancellation (stdlib only, like `_errors`).

On Python 3.11 ``asyncio.wait_for`` returns the inner result and drops a cancellation that
arrives just as the inner call finishes (CPython gh-86296, fixed in 3.12). A task looping
over such calls (a gateway poll every 20 ms, a heartbeat) then runs on after ``cancel()``,
and ``gather`` on it waits for ever. `stop_tasks` cancels again until each task has ended,
and gives up, saying which, after ``deadline_s``.
"""

from __future__ import annotations

import asyncio
import logging
from collections.abc import Iterable

__all__ = ["stop_tasks"]

log = logging.getLogger("transfertwin")


async def stop_tasks(tasks: Iterable[asyncio.Future], *, deadline_s: float = 10.0,
                     retry_s: float = 0.25) -> set[asyncio.Future]:
    """Cancel `tasks` and wait until all have ended, cancelling those still running again
    every `retry_s`; after `deadline_s` the rest are left running (logged) and returned.
    Exceptions the tasks ended with are retrieved (not re-raised)."""
    pending = {t for t in tasks if not t.done()}
    loop = asyncio.get_running_loop()
    end = loop.time() + deadline_s
    while pending:
        for task in pending:
            task.cancel()
        left = end - loop.time()
        if left <= 0:
            log.warning("%d task(s) still running after %.0f s of cancelling: %s", len(pending),
                        deadline_s, ", ".join(sorted(_name(t) for t in pending)))  # fmt: skip
            break
        done, pending = await asyncio.wait(pending, timeout=min(retry_s, left))
        for task in done:
            if not task.cancelled():
                task.exception()  # retrieved: not "never retrieved" at exit
    return pending


def _name(task: asyncio.Future) -> str:
    return task.get_name() if isinstance(task, asyncio.Task) else repr(task)
