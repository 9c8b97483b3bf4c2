"""Sessions to peer assets by id (`Peers`), kept open and reopened on failure: a secure
handshake costs far more than a call."""

from __future__ import annotations

import asyncio
import contextlib
from collections.abc import Callable
from typing import Any

from asyncua import ua

from transfertwin.cps.opcua import AssetClient

__all__ = ["Peers"]


class Peers:
    """Open sessions to peer assets by id, reopened after a failure.

    Args:
        resolve: Asset id -> its endpoint URL (None: not known now).
        open_session: (endpoint, asset id) -> an async context manager of a session.
    """

    def __init__(self, resolve: Callable[[str], str | None], open_session) -> None:
        self._resolve = resolve
        self._open = open_session
        self._stacks: dict[str, tuple[str, contextlib.AsyncExitStack, AssetClient]] = {}
        self._locks: dict[str, asyncio.Lock] = {}

    async def session(self, aid: str) -> AssetClient:
        """An open session with `aid` (ConnectionError when its endpoint is not known)."""
        url = self._resolve(aid)
        if url is None:
            raise ConnectionError(f"{aid}: endpoint not known (not discovered yet)")
        held = self._stacks.get(aid)
        if held is not None and held[0] == url:
            return held[2]
        await self.drop(aid)
        stack = contextlib.AsyncExitStack()
        try:
            client = await stack.enter_async_context(self._open(url, aid))
        except BaseException:
            await stack.aclose()
            raise
        self._stacks[aid] = (url, stack, client)
        return client

    async def open(self, aid: str) -> None:
        """Open the session with `aid` now if it is not open (as `call` would)."""
        lock = self._locks.setdefault(aid, asyncio.Lock())
        async with lock:
            try:
                await self.session(aid)
            except BaseException:
                await self.drop(aid)
                raise

    async def call(self, aid: str, operation: str, *args: object,
                   keep_if_slow: bool = False) -> Any:  # fmt: skip
        """Call `operation` on `aid`; a broken session is dropped and the error raised.
        With `keep_if_slow`, a call that ran out of time (the session's request timeout)
        keeps the session: the peer is busy, and a new handshake would cost it more."""
        lock = self._locks.setdefault(aid, asyncio.Lock())
        async with lock:
            try:
                return await (await self.session(aid)).call(operation, *args)
            except ua.UaStatusCodeError:  # the server answered: the session is fine
                raise
            except TimeoutError:
                if not keep_if_slow:
                    await self.drop(aid)
                raise
            except BaseException:
                await self.drop(aid)
                raise

    async def write(self, aid: str, prop: str, value: object) -> None:
        """Write an externally synchronised OperationalData property of `aid`."""
        lock = self._locks.setdefault(aid, asyncio.Lock())
        async with lock:
            try:
                await (await self.session(aid)).write("OperationalData", prop, value)
            except Exception:
                await self.drop(aid)
                raise

    async def read(self, aid: str, prop: str) -> Any:
        """Read an OperationalData property of `aid`."""
        lock = self._locks.setdefault(aid, asyncio.Lock())
        async with lock:
            try:
                return await (await self.session(aid)).read("OperationalData", prop)
            except Exception:
                await self.drop(aid)
                raise

    async def drop(self, aid: str) -> None:
        """Close the session with `aid`, if any."""
        held = self._stacks.pop(aid, None)
        if held is not None:
            with contextlib.suppress(Exception):
                await asyncio.wait_for(held[1].aclose(), 2.0)

    async def close(self) -> None:
        """Close every session, all at once (peers stopping at the same time as this one
        may each take the 2 s limit of `drop`)."""
        await asyncio.gather(*(self.drop(aid) for aid in list(self._stacks)))
