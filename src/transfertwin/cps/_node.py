"""One asset, one process: the node that serves a single asset of a floor (Ch. 3,
docs/architecture.md "Deployment").

A node starts the asset's secure OPC UA server (its AAS), joins the network through its
seed peers (decentralised discovery, `Discovery`), and keeps a **lease** at the knowledge
graph: every ``lease_s / 3`` seconds (jittered) it sends a heartbeat (`Heartbeat`): its
description and live state when they changed, a small renewal otherwise (`_lease`); a graph
that hears nothing for ``lease_s`` marks it offline (DDS liveliness: a missed lease is a
leave, no goodbye needed). On SIGINT/SIGTERM it announces its leave and exits. What the
asset does is its role (`transfertwin.cps._roles`); what must survive a crash is written
atomically to its state folder (`NodeState`).

Sessions to peers are kept open and reopened on failure (`Peers`): a secure handshake
costs far more than a call.
"""

from __future__ import annotations

import asyncio
import contextlib
import json
import logging
import os
import time
from collections.abc import Awaitable, Callable
from pathlib import Path
from typing import Any

from asyncua import ua

from transfertwin._atomic import write_atomic
from transfertwin._errors import InputError
from transfertwin.cps._asset_config import AssetConfig
from transfertwin.cps._floor_file import FloorSpec, load_floor
from transfertwin.cps._lease import NO_LEASE, Renewal, heartbeat_period
from transfertwin.cps._plant_assets import PROVENANCE as PLANT_PROVENANCE
from transfertwin.cps.aas import AssetDescriptor, build_representation, externally_synced
from transfertwin.cps.opcua import (
    AssetClient,
    AssetServer,
    Discovery,
    OperationRefused,
    ServerConfig,
    connect,
    load_credentials,
)

__all__ = ["AssetNode", "NodeState", "Peers", "heartbeat_payload", "prepare_forking"]

log = logging.getLogger("transfertwin.cps")

#: What an asset's AAS says its data come from, by HAL (the plant's seed and parameters are
#: not named; a remote asset's gateway is in its asset file, not in its AAS).
PROVENANCE = {"virtual": "transfertwin virtual model (MuJoCo)",
              "plant": PLANT_PROVENANCE,
              "remote": "physical asset behind a HAL gateway (OPC UA)"}  # fmt: skip


class NodeState:
    """A node's persisted state: one JSON document, rewritten atomically on every change.

    Args:
        path: The file (created with its folder on the first `save`).
        initial: The state when the file does not exist yet.
    """

    def __init__(self, path: Path, initial: dict[str, Any]) -> None:
        self.path = path
        self.data: dict[str, Any] = dict(initial)
        if path.is_file():
            self.data.update(json.loads(path.read_text()))

    def save(self) -> None:
        """Write the whole state (readers see the old file or the new one, never a part)."""
        self.path.parent.mkdir(parents=True, exist_ok=True)
        write_atomic(self.path, json.dumps(self.data, indent=1, sort_keys=True) + "\n")


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


def heartbeat_payload(desc: AssetDescriptor, endpoint: str, policy: str,
                      live: dict[str, Any]) -> str:  # fmt: skip
    """The JSON a node sends the knowledge graph with every heartbeat: who it is, where it
    answers, its process, and its live state (state, docked, possesses, location, pose)."""
    return json.dumps({
        "id": desc.asset_id, "kind": desc.kind.value, "class": desc.asset_class,
        "type": desc.physical_type.value if desc.physical_type else None,
        "capabilities": [c.value for c in desc.capabilities], "station": desc.station,
        "models": desc.models, "endpoint": endpoint, "security_policy": policy,
        "pid": os.getpid(), **live,
    })  # fmt: skip


class AssetNode:
    """The process of one asset (async context manager).

    Args:
        cfg: The asset's configuration file, parsed.
        floor: The floor (None: read ``cfg.floor_file``).
    """

    def __init__(self, cfg: AssetConfig, floor: FloorSpec | None = None) -> None:
        self.cfg = cfg
        self.floor = load_floor(cfg.floor_file, check_cores=False) if floor is None else floor
        by_id = {d.asset_id: d for d in self.floor.descriptors()}
        if cfg.asset_id not in by_id:
            raise InputError(f"asset {cfg.asset_id!r} is not on floor {self.floor.name} "
                        f"({cfg.floor_file})")  # fmt: skip
        self.desc = by_id[cfg.asset_id]
        self.descriptors = by_id
        self.credentials = None if cfg.insecure else load_credentials(cfg.credentials_file)
        self.server: AssetServer | None = None
        self.discovery: Discovery | None = None
        self.peers = Peers(self.endpoint_of, self._open)
        self._tasks: set[asyncio.Task] = set()
        self._beating: asyncio.Task | None = None
        self._known: dict[str, str] = {}  # asset id -> endpoint, from seeds and the graph
        self.role = _role_for(self)
        self.lease = Renewal(cfg.asset_id, os.getpid())
        self.started = time.monotonic()

    # -- life cycle -----------------------------------------------------------------------
    async def __aenter__(self) -> AssetNode:
        cfg = self.cfg
        rep = build_representation(self.desc, endpoint=cfg.endpoint,
                                   provenance=PROVENANCE[cfg.hal.kind])  # fmt: skip
        writable = {("OperationalData", p) for p in externally_synced(rep)}
        writable |= {("OperationalData", p) for p in self.role.writable()}
        scfg = ServerConfig(host=cfg.host, port=cfg.port, insecure=cfg.insecure,
                            cert_dir=cfg.cert_dir, trust_dir=cfg.trust_dir,
                            credentials=self.credentials)  # fmt: skip
        self.server = AssetServer(self.desc.asset_id, rep.submodels, scfg,
                                  self.role.handlers(), frozenset(writable))  # fmt: skip
        await self.server.__aenter__()
        await self.role.start()
        for url in cfg.seeds:
            self._known.setdefault(url.rsplit("/", 1)[-1], url)
        # a gossip round (a connection and a FindServers) pulls a peer's whole list: every
        # 5 s, and at most 10 entries a second on average (every 20 s at 200 assets), so an
        # idle asset spends next to nothing on it (docs/scaling.md). The endpoints of assets
        # that join reach every asset sooner through the graph's directory (heartbeats).
        self.discovery = Discovery(self.server, period_s=5.0, max_misses=2, entries_per_s=10.0)
        await self.discovery.join([u for u in cfg.seeds if u != cfg.endpoint], self._connector)
        self._beating = self.spawn(self._heartbeats())
        log.info("%s up at %s (pid %d)", self.desc.asset_id, self.server.endpoint, os.getpid())
        return self

    async def __aexit__(self, *exc: object) -> None:
        if self._beating is not None:  # no heartbeat after the leave: it would join again
            self._beating.cancel()
            await asyncio.wait({self._beating}, timeout=2.0)
        if self.desc.asset_id != "KG":  # the graph does not open a session to itself to leave
            with contextlib.suppress(Exception):  # announce the leave; the lease covers a crash
                await asyncio.wait_for(self.peers.call("KG", "Leave", self.desc.asset_id), 2.0)
        for task in list(self._tasks):
            task.cancel()
        await asyncio.gather(*self._tasks, return_exceptions=True)
        await self.role.stop()
        if self.discovery is not None:
            await self.discovery.stop()
        await self.peers.close()
        if self.server is not None:
            await self.server.__aexit__(None, None, None)
        log.info("%s down", self.desc.asset_id)

    def spawn(self, coro: Awaitable[object]) -> asyncio.Task:
        """Run `coro` as a task of this node (cancelled when the node stops)."""
        task = asyncio.ensure_future(coro)
        self._tasks.add(task)
        task.add_done_callback(self._tasks.discard)
        return task

    # -- peers ----------------------------------------------------------------------------
    def endpoint_of(self, aid: str) -> str | None:
        """The endpoint of asset `aid`: what discovery found, else what seeds/graph said."""
        if aid == self.desc.asset_id and self.server is not None:
            return self.server.endpoint
        if self.discovery is not None:
            for peer in self.discovery.peers.values():
                if peer.asset_id == aid:
                    return peer.url
        return self._known.get(aid)

    def learn(self, aid: str, endpoint: str) -> None:
        """Remember where `aid` answers (from the graph's status)."""
        self._known[aid] = endpoint

    def _open(self, url: str, aid: str, timeout_s: float = 10.0):
        cfg = self.cfg
        # the graph's session carries heartbeats, which tell a dead connection soon enough:
        # asyncua's own probe of it (a read every 10 s by default) would be one more call
        # per asset at the one lease holder
        watchdog = max(10.0, 3.0 * cfg.lease_s) if aid == "KG" else None
        return connect(url, aid, credentials=self.credentials, role="operator",
                       cert_dir=cfg.cert_dir, insecure=cfg.insecure, timeout_s=timeout_s,
                       watchdog_s=watchdog)  # fmt: skip

    def _connector(self, url: str):
        aid = url.rsplit("/", 1)[-1]
        if aid == "KG" and self.desc.asset_id != "KG":
            return self._graph_session()  # the heartbeats' session: one handshake, not two
        return self._open(url, aid, 5.0)

    @contextlib.asynccontextmanager
    async def _graph_session(self):
        """The kept session with the graph (opened if need be), not closed after use."""
        await asyncio.wait_for(self.peers.open("KG"), 15.0)
        yield await self.peers.session("KG")

    # -- lease ----------------------------------------------------------------------------
    async def _heartbeats(self) -> None:
        period = heartbeat_period(self.cfg.lease_s)
        while True:
            if self.desc.asset_id == "KG":
                await self.role.beat_self()
            else:
                try:
                    await self._beat()
                except Exception as exc:  # the graph is away: keep serving, keep trying
                    log.debug("%s: heartbeat not delivered: %s", self.desc.asset_id, exc)
                if asyncio.current_task().cancelling():
                    # stopped while a call's answer had already come: wait_for (Python
                    # 3.11) returned it and dropped the cancellation; the node waits for us
                    raise asyncio.CancelledError
            await asyncio.sleep(self.lease.pause(period))

    async def _beat(self) -> None:
        """One heartbeat: a renewal, or the full description when it changed or the graph
        holds no lease for this process (then sent at once)."""
        live = {"hal": self.cfg.hal.kind, **await self.role.live()}
        payload = heartbeat_payload(self.desc, self.server.endpoint,
                                    self.server.security_policy, live)  # fmt: skip
        # opening the session (a secure handshake) has its own, longer limit: a graph busy
        # with many joining assets must not see each handshake cancelled by the heartbeat's
        # limit and started again (no one would ever get through)
        await asyncio.wait_for(self.peers.open("KG"), 15.0)
        for _ in range(2):
            try:  # a graph too busy to answer within the request timeout keeps the session
                reply = await self.peers.call("KG", "Heartbeat", self.lease.request(payload),
                                              keep_if_slow=True)  # fmt: skip
            except OperationRefused as exc:
                if exc.status != NO_LEASE:
                    raise
                self.lease.refused()
                continue
            endpoints = self.lease.answered(reply)
            if endpoints:
                self._known.update(endpoints)
            return
        raise ConnectionError("the graph refused the full heartbeat too")


def prepare_forking() -> None:
    """Make this process the parent of asset processes forked from it: import what every
    asset needs (the node, the roles of units, objects and the graph; not the simulation,
    which only a module imports), build the OPC UA standard address space's template, and
    move all of it out of the collector's reach (`gc.freeze`), so that the forked processes
    share those pages copy-on-write instead of each building its own (about 60 of the
    90 MB of an object's process). Must run before any event loop or thread starts."""
    import gc

    from transfertwin.cps import _roles  # noqa: F401  (imported for the children)
    from transfertwin.cps.opcua import build_standard_address_space

    build_standard_address_space()
    gc.collect()
    gc.freeze()


def _role_for(node: AssetNode):
    from transfertwin.cps import _roles

    return _roles.role_for(node)
