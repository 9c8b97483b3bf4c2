"""One asset, one node: the node that serves a single asset of a floor (Ch. 3,
docs/architecture.md "Deployment"). A floor runs one node per process, or all of its nodes
in one event loop (`cps up --single-process`): the node is the same.

A node starts the asset's secure OPC UA server (its AAS), joins the network through its
seed peers (decentralised discovery, `Discovery`), and keeps a **lease** at the knowledge
graph: every ``lease_s / 3`` seconds (jittered) it sends a heartbeat (`Heartbeat`): its
description and live state when they changed, a small renewal otherwise (`_lease`); a graph
that hears nothing for ``lease_s`` marks it offline (DDS liveliness: a missed lease is a
leave, no goodbye needed). On SIGINT/SIGTERM it announces its leave and exits. What the
asset does is its role, made by the factory the node is handed (`transfertwin.cps.roles`
holds the registry); what must survive a crash is written atomically to its state folder
(`NodeState`). Sessions to peers are kept open and reopened on failure (`Peers`).
"""

from __future__ import annotations

import asyncio
import contextlib
import json
import logging
import os
import time
from collections.abc import Awaitable, Callable
from typing import Any

from basyx.aas import model

from transfertwin._aio import stop_tasks
from transfertwin._errors import InputError
from transfertwin.cps.aas import (
    Arg,
    AssetDescriptor,
    OperationSpec,
    build_representation,
    externally_synced,
    operation,
    semantic,
    submodel_iri,
)
from transfertwin.cps.floor import PROVENANCE, AssetConfig, FloorSpec, load_floor
from transfertwin.cps.node._identity import peer_roles
from transfertwin.cps.node._lease import NO_LEASE, Renewal, heartbeat_period, instance_id
from transfertwin.cps.node._peers import Peers
from transfertwin.cps.node._role import Role
from transfertwin.cps.opcua import (
    AssetServer,
    Discovery,
    OperationRefused,
    ServerConfig,
    connect,
    load_users,
)

__all__ = ["LIFECYCLE", "SHUTDOWN", "AssetNode", "RoleFactory", "heartbeat_payload",
           "lifecycle_submodel"]  # fmt: skip

log = logging.getLogger("transfertwin.cps")

#: The operation every asset offers the operator role: stop serving (announce the leave and
#: end the process), so a floor is stopped over OPC UA from any host (`cps down`). It is
#: served in a submodel of its own, ``Lifecycle`` (the process, not the asset: an object
#: of Table 3.1 has no ControlInterface, and its process still stops).
SHUTDOWN = OperationSpec(
    "Shutdown", (), (Arg("ok", "xs:boolean"),),
    "Stop this asset: it answers, announces its leave and ends its process (operator role).",
)

#: The submodel of the process's own operations (`SHUTDOWN`).
LIFECYCLE = "Lifecycle"

#: Seconds between a Shutdown's answer and the stop (the answer must get out first).
SHUTDOWN_DELAY_S = 0.2

def lifecycle_submodel(asset_id: str) -> model.Submodel:
    """The submodel `LIFECYCLE` every asset's server has besides its AAS (`SHUTDOWN`)."""
    return model.Submodel(submodel_iri(asset_id, LIFECYCLE), id_short=LIFECYCLE,
                          semantic_id=semantic(LIFECYCLE),
                          submodel_element=[operation(SHUTDOWN)])  # fmt: skip


#: Makes the role of a node's asset (`transfertwin.cps.roles.role_for`).
RoleFactory = Callable[["AssetNode"], Role]


def heartbeat_payload(desc: AssetDescriptor, endpoint: str, policy: str,
                      live: dict[str, Any], instance: str = "") -> str:  # fmt: skip
    """The JSON a node sends the knowledge graph with every heartbeat: who it is, where it
    answers, this start of its process (`instance`; the pid is shown, never a key: pids
    repeat across hosts), and its live state (state, docked, possesses, location, pose)."""
    return json.dumps({
        "id": desc.asset_id, "kind": desc.kind.value, "class": desc.asset_class,
        "role_class": desc.role_class,
        "type": desc.physical_type.value if desc.physical_type else None,
        "capabilities": [c.value for c in desc.capabilities], "station": desc.station,
        "constraints": [[c.value, name, value] for c, name, value in desc.constraints],
        "models": desc.models, "endpoint": endpoint, "security_policy": policy,
        "instance": instance, "pid": os.getpid(), **live,
    })  # fmt: skip


class AssetNode:
    """The process of one asset (async context manager).

    Args:
        cfg: The asset's configuration file, parsed.
        roles: Makes the asset's role (`transfertwin.cps.roles.role_for`).
        floor: The floor (None: read ``cfg.floor_file``).
    """

    def __init__(self, cfg: AssetConfig, roles: RoleFactory,
                 floor: FloorSpec | None = None) -> None:  # fmt: skip
        self.cfg = cfg
        self.floor = load_floor(cfg.floor_file, check_cores=False) if floor is None else floor
        by_id = {d.asset_id: d for d in self.floor.descriptors()}
        if cfg.asset_id not in by_id:
            raise InputError(f"asset {cfg.asset_id!r} is not on floor {self.floor.name} "
                        f"({cfg.floor_file})")  # fmt: skip
        self.desc = by_id[cfg.asset_id]
        self.descriptors = by_id
        # the people's users (a user table: hashes only); the node itself is its certificate
        self.credentials = None if cfg.insecure else load_users(cfg.credentials_file)
        self.server: AssetServer | None = None
        self.discovery: Discovery | None = None
        self.peers = Peers(self.endpoint_of, self._open)
        self._tasks: set[asyncio.Task] = set()
        self._beating: asyncio.Task | None = None
        self._known: dict[str, str] = {}  # asset id -> endpoint, from seeds and the graph
        self.role = roles(self)
        self.instance = instance_id()  # this start of the asset's process, on any host
        self.lease = Renewal(cfg.asset_id, self.instance)
        self.started = time.monotonic()
        #: Set when an operator asked this asset to stop (`SHUTDOWN`); whoever runs the node
        #: (its process, or a `LocalFloor`) waits on it and stops the node.
        self.shutdown = asyncio.Event()

    # -- life cycle -----------------------------------------------------------------------
    async def __aenter__(self) -> AssetNode:
        cfg = self.cfg
        rep = build_representation(self.desc, endpoint=cfg.endpoint,
                                   provenance=PROVENANCE[cfg.hal.kind])  # fmt: skip
        for spec in self.role.operations():
            rep.submodel("ControlInterface").submodel_element.add(operation(spec))
        writable = {("OperationalData", p) for p in externally_synced(rep)}
        writable |= {("OperationalData", p) for p in self.role.writable()}
        scfg = ServerConfig(host=cfg.host, port=cfg.port, insecure=cfg.insecure,
                            cert_dir=cfg.cert_dir, trust_dir=cfg.trust_dir,
                            credentials=self.credentials,
                            peer_roles=peer_roles(self.descriptors.values()))  # fmt: skip
        lifecycle = lifecycle_submodel(self.desc.asset_id)
        self.server = AssetServer(self.desc.asset_id, (*rep.submodels, lifecycle), scfg,
                                  {**self.role.handlers(), "Shutdown": self._shutdown},
                                  frozenset(writable))  # fmt: skip
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
            await stop_tasks([self._beating], deadline_s=2.0)
        if self.desc.asset_id != "KG":  # the graph does not open a session to itself to leave
            with contextlib.suppress(Exception):  # announce the leave; the lease covers a crash
                await asyncio.wait_for(self.peers.call("KG", "Leave", self.desc.asset_id), 2.0)
        await stop_tasks(list(self._tasks))  # cancelled again if one swallows it (3.11)
        await self.role.stop()
        if self.discovery is not None:
            await self.discovery.stop()
        await self.peers.close()
        if self.server is not None:
            await self.server.__aexit__(None, None, None)
        log.info("%s down", self.desc.asset_id)

    async def _shutdown(self) -> bool:
        """`SHUTDOWN`: answer, then set `shutdown` (the runner stops the node)."""
        log.info("%s: shutdown asked over OPC UA", self.desc.asset_id)
        asyncio.get_running_loop().call_later(SHUTDOWN_DELAY_S, self.shutdown.set)
        return True

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

    async def graph_status(self, timeout_s: float = 5.0) -> list[dict[str, Any]] | None:
        """Every asset as the knowledge graph's ``Status`` lists it (id, class, online,
        address, ...), the addresses remembered (`learn`); None when the graph does not
        answer within `timeout_s`."""
        try:
            status = json.loads(await asyncio.wait_for(self.peers.call("KG", "Status"),
                                                       timeout_s))  # fmt: skip
        except Exception as exc:
            log.debug("%s: knowledge graph not answering: %s", self.desc.asset_id, exc)
            return None
        for a in status["assets"]:
            if a.get("address"):
                self.learn(a["id"], a["address"])
        return status["assets"]

    def open_session(self, aid: str, timeout_s: float):
        """A session of its own with `aid` whose requests may take `timeout_s` (a call that
        runs long, such as an experiment cycle), as an async context manager."""
        url = self.endpoint_of(aid)
        if url is None:
            raise ConnectionError(f"{aid}: endpoint not known (not discovered yet)")
        return self._open(url, aid, timeout_s)

    def _open(self, url: str, aid: str, timeout_s: float = 10.0):
        cfg = self.cfg
        # the graph's session carries heartbeats, which tell a dead connection soon enough:
        # asyncua's own probe of it (a read every 10 s by default) would be one more call
        # per asset at the one lease holder
        watchdog = max(10.0, 3.0 * cfg.lease_s) if aid == "KG" else None
        # the node is its certificate (an X.509 identity, `peer_roles`), no password; the
        # server must be the asset `aid` under the floor's CA (`trust_dir`)
        return connect(url, aid, credentials=None, role="operator", cert_dir=cfg.cert_dir,
                       certificate=cfg.asset_id, trust_dir=cfg.trust_dir,
                       insecure=cfg.insecure, timeout_s=timeout_s,
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
                                    self.server.security_policy, live,
                                    self.instance)  # fmt: skip
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
