"""Decentralised discovery: every asset knows its peers; no central registry (Sec. 5.3).

Each asset server answers the standard OPC UA FindServers service with the servers it
knows. An asset that joins registers itself (RegisterServer2) at one or more seed peers
and takes their lists; then every asset periodically asks each known peer for its list
(pull gossip), so a newcomer spreads to all within a few rounds. A peer that cannot be
reached for `max_misses` rounds in a row is dropped: that is how a leaving asset is
noticed. Listeners hear about every join and leave.

On a secure floor a peer is taken only once its server proved to be the asset it names:
an entry heard of (gossip, or a registration, which asyncua accepts on any channel, even
without security) is a *candidate* until a round asks it, and asking it checks the
certificate of its SignAndEncrypt endpoint against the trust list (the floor's CA, not
revoked, valid now, naming the entry's URI: `TrustList.server_validator`). A candidate
that fails is dropped and never passed on (it is taken off the server's FindServers
answer too); one that answers becomes a peer. Asking costs the connection a round makes
anyway (GetEndpoints and FindServers on one channel).
"""

from __future__ import annotations

import asyncio
import logging
import time
from collections.abc import Callable, Iterable
from contextlib import AbstractAsyncContextManager
from dataclasses import dataclass, field

from asyncua import Client, ua
from asyncua.common.utils import ServiceError
from asyncua.crypto import uacrypto
from asyncua.crypto.security_policies import SecurityPolicyBasic256Sha256

from transfertwin._aio import stop_tasks
from transfertwin.cps.opcua._client import AssetClient, UntrustedServer, trust_list
from transfertwin.cps.opcua._server import AssetServer

__all__ = ["Discovery", "Peer"]

log = logging.getLogger(__name__)

Connector = Callable[[str], AbstractAsyncContextManager[AssetClient]]


@dataclass(frozen=True)
class Peer:
    """A known asset server: its application URI and discovery URL."""

    uri: str
    url: str

    @property
    def asset_id(self) -> str:
        """The asset id encoded in a transfertwin application URI."""
        return self.uri.rsplit(":", 1)[-1]


@dataclass
class Discovery:
    """The discovery agent of one asset.

    Args:
        server: The asset's running server (its FindServers answers with `peers`).
        period_s: Gossip period (the shortest, with `entries_per_s`).
        max_misses: Rounds a peer may be unreachable before it counts as gone.
        entries_per_s: If set, the period stretches to ``len(peers) / entries_per_s``
            when that is longer: a round pulls a peer's whole list, so this bounds what one
            asset's gossip costs it and the peers it asks on a large floor (0: fixed).
        on_change: Called with ('join' | 'leave', peer) for every change seen here.
    """

    server: AssetServer
    period_s: float = 0.5
    max_misses: int = 2
    tombstone_s: float = 10.0
    on_change: Callable[[str, Peer], None] | None = None
    entries_per_s: float = 0.0
    peers: dict[str, Peer] = field(default_factory=dict)
    candidates: dict[str, Peer] = field(default_factory=dict)
    _misses: dict[str, int] = field(default_factory=dict)
    _gone: dict[str, float] = field(default_factory=dict)  # uri -> when it was dropped
    _turn: int = 0
    _task: asyncio.Task | None = None

    @property
    def me(self) -> Peer:
        """This asset as a peer."""
        return Peer(f"urn:transfertwin:{self.server.asset_id}", self.server.endpoint)

    @property
    def verifies(self) -> bool:
        """Whether peers must prove who they are (a secure server: yes)."""
        return self.server.config is not None and not self.server.config.insecure

    def _add(self, peer: Peer, *, direct: bool = False, verified: bool = False) -> None:
        if peer.uri == self.me.uri:
            return
        known = self.peers.get(peer.uri)
        if known is not None and (known.url == peer.url or not direct):
            return
        dropped = self._gone.get(peer.uri)
        if dropped is not None and not direct and time.monotonic() - dropped < self.tombstone_s:
            return  # hearsay about a peer we saw leave; only its own re-registration counts
        if self.verifies and not verified:
            self.candidates.setdefault(peer.uri, peer)  # asked (and so checked) in a round
            return
        self.candidates.pop(peer.uri, None)
        self._gone.pop(peer.uri, None)
        self.peers[peer.uri] = peer
        self._misses[peer.uri] = 0
        self.server.register_peer(peer.uri, peer.url, peer.asset_id)
        log.info("%s discovered %s at %s", self.server.asset_id, peer.asset_id, peer.url)
        if self.on_change is not None and known is None:
            self.on_change("join", peer)

    def _drop(self, uri: str) -> None:
        peer = self.peers.pop(uri)
        self._misses.pop(uri, None)
        self._gone[uri] = time.monotonic()
        self.server.unregister_peer(uri)
        log.info("%s noticed %s left", self.server.asset_id, peer.asset_id)
        if self.on_change is not None:
            self.on_change("leave", peer)

    async def _ask(self, url: str, uri: str | None = None) -> list[Peer]:
        """The peers `url` knows (FindServers). On a secure floor the server is checked
        first, on the same channel (GetEndpoints): its certificate must be trusted here
        and name `uri` (default: the URI of the asset the URL names), else
        `UntrustedServer`."""
        uri = uri or f"urn:transfertwin:{url.rstrip('/').rsplit('/', 1)[-1]}"
        client = Client(url=url, timeout=2)

        async def ask() -> list[ua.ApplicationDescription]:
            await client.connect_socket()
            try:
                await client.send_hello()
                await client.open_secure_channel()
                try:
                    if self.verifies:
                        await self._check(url, uri, await client.get_endpoints())
                    return await client.find_servers()
                finally:
                    await client.close_secure_channel()
            finally:
                client.disconnect_socket()

        servers = await asyncio.wait_for(ask(), 3)
        return [Peer(s.ApplicationUri, s.DiscoveryUrls[0]) for s in servers if s.DiscoveryUrls]

    async def _check(self, url: str, uri: str, endpoints: list) -> None:
        """UntrustedServer unless the SignAndEncrypt endpoint's certificate is trusted
        here and names `uri`."""
        mode = ua.MessageSecurityMode.SignAndEncrypt
        try:
            endpoint = Client.find_endpoint(endpoints, mode, SecurityPolicyBasic256Sha256.URI)
        except ua.UaError:
            raise UntrustedServer(url, uri, ua.StatusCodes.BadSecurityPolicyRejected) from None
        trust = trust_list(self.server.config.trust_folder)
        cert = uacrypto.x509_from_der(endpoint.ServerCertificate)
        try:
            await trust.server_validator(uri)(cert, endpoint.Server)
        except ServiceError as exc:
            raise UntrustedServer(url, uri, exc.code) from None

    async def _announce(self, url: str, connector: Connector) -> None:
        registered = ua.RegisteredServer()
        registered.ServerUri = self.me.uri
        registered.ProductUri = "urn:transfertwin"
        registered.ServerNames = [ua.LocalizedText(self.server.asset_id)]
        registered.ServerType = ua.ApplicationType.Server
        registered.DiscoveryUrls = [self.me.url]
        registered.IsOnline = True
        params = ua.RegisterServer2Parameters()
        params.Server = registered
        params.DiscoveryConfiguration = []
        async with connector(url) as session:
            await session.client.uaclient.register_server2(params)

    async def join(self, seeds: Iterable[str], connector: Connector) -> None:
        """Register at the seed peers, learn their lists, start gossiping.

        Args:
            seeds: Discovery URLs of peers to start from.
            connector: Opens an operator session to a peer URL (RegisterServer2 needs it).
        """
        for url in seeds:
            try:
                await self._announce(url, connector)
                found = await self._ask(url)
                self._add(Peer(f"urn:transfertwin:{url.rsplit('/', 1)[-1]}", url),
                          verified=True)  # fmt: skip
                for peer in found:
                    self._add(peer)
            except (TimeoutError, OSError, ua.UaError) as exc:
                log.warning("%s: seed %s unreachable: %s", self.server.asset_id, url, exc)
        self._task = asyncio.ensure_future(self._gossip())

    async def round(self) -> None:
        """One gossip round: take the registrations our own server received (candidates,
        off its FindServers answer until checked), then ask the next known peer or
        candidate (round robin) for its list, which checks it; drop a peer silent
        `max_misses` times, and a candidate that is not who it says at once.

        One peer per round keeps the traffic linear in the number of assets; every peer is
        visited once per len(peers) rounds.
        """
        for uri, url in self.server.registered_peers():
            if uri not in self.peers and uri not in self._gone:
                if self.verifies:
                    self.server.unregister_peer(uri)
                self._add(Peer(uri, url), direct=True)
            elif uri in self.peers and self.peers[uri].url != url:  # moved: check it again
                self.server.register_peer(uri, self.peers[uri].url, self.peers[uri].asset_id)
                self.candidates[uri] = Peer(uri, url)
        everyone = {**self.candidates, **self.peers}
        if not everyone:
            return
        uris = sorted(everyone)
        self._turn = (self._turn + 1) % len(uris)
        uri = uris[self._turn]
        peer = self.candidates.get(uri) or self.peers[uri]
        try:
            found = await self._ask(peer.url, uri)
        except UntrustedServer as exc:
            log.warning("%s: refused %s: %s", self.server.asset_id, uri, exc)
            if self.candidates.get(uri) == peer:
                del self.candidates[uri]
                return
            self._misses[uri] = self.max_misses  # a peer whose certificate went bad
            self._drop(uri)
            return
        except (TimeoutError, OSError, ua.UaError, ConnectionError):
            self._misses[uri] = self._misses.get(uri, 0) + 1
            if self._misses[uri] >= self.max_misses:
                if uri in self.peers and self.peers[uri] == peer:
                    self._drop(uri)
                else:
                    self.candidates.pop(uri, None)
                    self._misses.pop(uri, None)
            return
        self._misses[uri] = 0
        if self.candidates.get(uri) == peer:
            self._add(peer, direct=True, verified=True)
        for other in found:
            self._add(other)

    def pause(self) -> float:
        """Seconds until the next round: `period_s`, stretched with the number of peers
        when `entries_per_s` is set."""
        if self.entries_per_s > 0:
            return max(self.period_s, len(self.peers) / self.entries_per_s)
        return self.period_s

    async def _gossip(self) -> None:
        while True:
            await asyncio.sleep(self.pause())
            await self.round()

    async def stop(self) -> None:
        """Stop gossiping (the server's going away is what peers notice)."""
        if self._task is not None:
            await stop_tasks([self._task])
            self._task = None
