"""Shared across the CPS tests of one run: credentials, certificates (server and client
application certificates, the trust list) and one asset server.

RSA key generation and a server's start are the slow parts of a CPS test; every test used
to make its own. The server runs on an event loop of its own in a thread, so tests that
each drive their clients with `asyncio.run` can share it over loopback TCP.
"""

from __future__ import annotations

import asyncio
import threading
from collections.abc import Awaitable, Callable, Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import basyx.aas.model as aas
import pytest

from transfertwin.cps.aas._demo import demo_descriptors
from transfertwin.cps.aas._representation import build_representation, externally_synced
from transfertwin.cps.opcua import (
    ROLES,
    AssetServer,
    Credentials,
    ServerConfig,
    ensure_certificate,
    new_credentials,
    trust_certificate,
)


@dataclass(frozen=True)
class Pki:
    """A CPS-like workdir: ``root/certs`` (application certificates) and
    ``root/certs/trusted`` (the trust list, holding the client certificates of every role)."""

    root: Path
    credentials: Credentials

    @property
    def cert_dir(self) -> Path:
        return self.root / "certs"

    @property
    def trust_dir(self) -> Path:
        return self.cert_dir / "trusted"

    def config(self, **kw: Any) -> ServerConfig:
        return ServerConfig(cert_dir=self.cert_dir, credentials=self.credentials, **kw)

    def client_kw(self) -> dict[str, Any]:
        return {"credentials": self.credentials, "cert_dir": self.cert_dir}


@pytest.fixture(scope="session")
def pki(tmp_path_factory: pytest.TempPathFactory) -> Pki:
    """Credentials and trusted client certificates made once per test run."""
    out = Pki(tmp_path_factory.mktemp("pki"), new_credentials())

    async def make() -> None:
        for role in ROLES:
            cert, _ = await ensure_certificate(out.cert_dir, f"client-{role}")
            trust_certificate(out.trust_dir, cert)

    asyncio.run(make())
    return out


class ServedAsset:
    """An asset server on its own event loop in a daemon thread.

    Operation handlers can be swapped per test (`handle`); `run` executes a coroutine on
    the server's loop (server-side `get`/`set`).
    """

    def __init__(self, asset_id: str, config: ServerConfig) -> None:
        rep = build_representation(next(d for d in demo_descriptors() if d.asset_id == asset_id))
        self.writable = sorted(("OperationalData", p) for p in externally_synced(rep))
        self.methods = [e.id_short for e in rep.submodel("ControlInterface").submodel_element
                        if isinstance(e, aas.Operation)]  # fmt: skip
        self._behaviour: dict[str, Callable[..., Awaitable[Any]]] = {}
        handlers = {op: self._dispatcher(op) for op in self.methods}
        self.server = AssetServer(
            asset_id, rep.submodels, config, handlers, frozenset(self.writable)
        )
        self._loop = asyncio.new_event_loop()
        self._thread = threading.Thread(target=self._loop.run_forever, daemon=True)

    def _dispatcher(self, op: str) -> Callable[..., Awaitable[Any]]:
        async def call(*args: Any) -> Any:
            fn = self._behaviour.get(op)
            if fn is None:
                raise ValueError(f"{op} has no handler in this test")
            return await fn(*args)

        return call

    def handle(self, op: str, fn: Callable[..., Awaitable[Any]] | None) -> None:
        if fn is None:
            self._behaviour.pop(op, None)
        else:
            self._behaviour[op] = fn

    @property
    def endpoint(self) -> str:
        return self.server.endpoint

    def run(self, coro: Awaitable[Any], timeout: float = 60) -> Any:
        return asyncio.run_coroutine_threadsafe(coro, self._loop).result(timeout)

    def start(self) -> ServedAsset:
        self._thread.start()
        self.run(self.server.__aenter__())
        return self

    def stop(self) -> None:
        self.run(self.server.__aexit__(None, None, None))
        self._loop.call_soon_threadsafe(self._loop.stop)
        self._thread.join(10)
        self._loop.close()


@pytest.fixture(scope="session")
def _tu_a_server(pki: Pki) -> Iterator[ServedAsset]:
    served = ServedAsset("TU_A", pki.config()).start()
    yield served
    served.stop()


@pytest.fixture
def tu_a(_tu_a_server: ServedAsset) -> Iterator[ServedAsset]:
    """The shared TU_A server, its handlers reset after the test."""
    yield _tu_a_server
    _tu_a_server._behaviour.clear()
