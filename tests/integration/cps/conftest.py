"""Shared across the CPS tests of one run: credentials, certificates (server and client
application certificates, the trust list), one asset server and one whole CPS.

RSA key generation and a server's start are the slow parts of a CPS test; every test used
to make its own. The server runs on an event loop of its own in a thread, so tests that
each drive their clients with `asyncio.run` can share it over loopback TCP.

The whole CPS is one `cps up --plant-seed` subprocess (`plant_cps`) for the CLI tests and the
plant tests. It starts when the first test of this folder runs, and the tests that use it run
after the folder's other tests, so it comes up while they run. The test that stops it
(SIGTERM) runs last; a test that needs it after that gets a new one. A module's process
floor (``EARLY_FLOOR``: `cps up --floor --detach`) starts then too (`early_floor`).
"""

from __future__ import annotations

import asyncio
import shutil
import threading
from collections.abc import Awaitable, Callable, Iterator
from contextlib import suppress
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import basyx.aas.model as aas
import pytest

from tests.integration.cps._cli import PLANT_SEED, RunningCps, early_floor, early_floors
from transfertwin.cps import plant_descriptors
from transfertwin.cps.aas._demo import demo_descriptors
from transfertwin.cps.aas._representation import build_representation, externally_synced
from transfertwin.cps.opcua import (
    ROLES,
    AssetServer,
    Credentials,
    FloorCA,
    ServerConfig,
    init_ca,
    install_certificate,
    new_credentials,
    new_request,
)

_HERE = Path(__file__).resolve().parent


@dataclass(frozen=True)
class Pki:
    """A CPS-like workdir: a floor CA (``root/ca``), ``root/certs`` (application
    certificates, the CA's: a server started with `config` gets its certificate from it)
    and ``root/certs/trusted`` (the trust list: the CA and its CRL)."""

    root: Path
    credentials: Credentials
    ca: FloorCA

    @property
    def cert_dir(self) -> Path:
        return self.root / "certs"

    @property
    def trust_dir(self) -> Path:
        return self.cert_dir / "trusted"

    def config(self, **kw: Any) -> ServerConfig:
        given = {"cert_dir": self.cert_dir, "credentials": self.credentials, "issuer": self.ca}
        return ServerConfig(**{**given, **kw})

    def client_kw(self) -> dict[str, Any]:
        return {"credentials": self.credentials, "cert_dir": self.cert_dir}


@pytest.fixture(scope="session")
def pki(tmp_path_factory: pytest.TempPathFactory) -> Pki:
    """Credentials, a CA and its client certificates made once per test run."""
    root = tmp_path_factory.mktemp("pki")
    out = Pki(root, new_credentials(), init_ca(root / "ca"))
    for role in ROLES:
        name = f"client-{role}"
        install_certificate(out.cert_dir, name, out.ca.issue(new_request(out.cert_dir, name)))
    out.ca.install(out.trust_dir)
    return out


@pytest.fixture(scope="session")
def cps_certs(tmp_path_factory: pytest.TempPathFactory) -> Callable[[Path], Path]:
    """A floor CA and the certificates it issued to every asset of a CPS (the demo's and
    the plant's) and to its clients, made once per run: a function that puts a copy of
    them into a CPS workdir (created: ``ca/``, ``certs/``, ``assets/<id>/certs/``) and
    returns it. The CPS finds them current and makes no keys."""
    root = tmp_path_factory.mktemp("cps-certs")
    ca = init_ca(root / "ca")
    names = [d.asset_id for d in (*demo_descriptors(), *plant_descriptors())]
    folders = {name: root / "assets" / name / "certs" for name in names}
    folders |= {f"client-{role}": root / "certs" for role in ROLES}
    for name, folder in folders.items():
        install_certificate(folder, name, ca.issue(new_request(folder, name)))

    def workdir(path: Path) -> Path:
        for part in ("ca", "certs", "assets"):
            shutil.copytree(root / part, path / part)
        return path

    return workdir


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


# -- one whole CPS (`cps up --plant-seed`) per test run ---------------------------------------
class _SharedCps:
    def __init__(self) -> None:
        self.factory: pytest.TempPathFactory | None = None
        self.certs: Callable[[Path], Path] | None = None
        self.cps: RunningCps | None = None
        self.stopped = False

    def launch(self) -> RunningCps:
        """The running CPS; a new one if there is none or a test stopped it."""
        if self.cps is None or self.stopped:
            assert self.factory is not None
            assert self.certs is not None
            wd = self.certs(self.factory.mktemp("plant-cps") / "wd")
            self.cps = RunningCps(wd, "--single-process", "--plant-seed", str(PLANT_SEED))
            self.stopped = False
        return self.cps

    def close(self) -> None:
        if self.cps is not None and self.cps.running:
            with suppress(Exception):
                self.cps.stop()


_SHARED = _SharedCps()
_USES, _STOPS = "plant_cps", "plant_cps_to_stop"


def _in_folder(item: pytest.Item) -> bool:
    return _HERE in Path(str(item.path)).resolve().parents


def _early_floor(item: pytest.Item) -> bool:
    return getattr(getattr(item, "module", None), "EARLY_FLOOR", None) is not None


def pytest_collection_modifyitems(config: pytest.Config, items: list[pytest.Item]) -> None:
    """This folder's tests that use the shared CPS after its other tests (which run while
    it comes up); the one that stops it after them. The tests of a module whose process
    floor starts ahead (``EARLY_FLOOR``) just before those, for the same reason."""
    users = [i for i in items if _in_folder(i) and _USES in getattr(i, "fixturenames", ())]
    ids = {id(i) for i in users}
    floors = [i for i in items if _in_folder(i) and _early_floor(i) and id(i) not in ids]
    if not users and not floors:
        return
    ids |= {id(i) for i in floors}
    first = min(k for k, i in enumerate(items) if id(i) in ids)
    rest = [i for i in items if id(i) not in ids]
    others = [k for k, i in enumerate(rest) if _in_folder(i)]
    at = others[-1] + 1 if others else min(first, len(rest))
    stoppers = [i for i in users if _STOPS in i.fixturenames]
    ordered = floors + [i for i in users if _STOPS not in i.fixturenames] + stoppers
    items[:] = rest[:at] + ordered + rest[at:]


@pytest.fixture(scope="session", autouse=True)
def _shared_cps_launch(
    request: pytest.FixtureRequest, tmp_path_factory: pytest.TempPathFactory
) -> Iterator[None]:
    """Start the shared CPS (without waiting for it) when the first test here runs, if a
    selected test uses it, and the process floors of the selected tests' modules
    (``EARLY_FLOOR``); stop them at the end of the run."""
    _SHARED.factory = tmp_path_factory
    if any(_USES in getattr(i, "fixturenames", ()) for i in request.session.items):
        _SHARED.certs = request.getfixturevalue("cps_certs")
        _SHARED.launch()
    for item in request.session.items:
        spec = getattr(getattr(item, "module", None), "EARLY_FLOOR", None)
        if spec is not None and _in_folder(item):
            early_floor(tmp_path_factory, *spec)
    yield
    _SHARED.close()
    for floor in early_floors():  # a floor whose tests did not take it down
        if not floor.down:
            with suppress(Exception):
                floor.result()
                floor.stop()


@pytest.fixture
def plant_cps() -> RunningCps:
    """The shared `cps up --plant-seed PLANT_SEED`, up (14 demo assets and 4 physical
    units). Tests must leave it usable for the others: orders move objects, and only the
    test that asks for `plant_cps_to_stop` may stop it."""
    return _SHARED.launch().wait_up()


@pytest.fixture
def plant_cps_to_stop(plant_cps: RunningCps) -> Iterator[RunningCps]:
    """The shared CPS, for a test that stops it (ordered last; the next user gets a new
    one)."""
    _SHARED.stopped = True
    yield plant_cps
