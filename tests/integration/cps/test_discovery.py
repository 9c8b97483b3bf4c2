"""Decentralised discovery: assets find each other through any peer, joins and leaves are
noticed by every other asset, with no central registry."""

from __future__ import annotations

import asyncio

from transfertwin.cps import AssetServer, build_representation, connect
from transfertwin.cps.aas._demo import demo_descriptors
from transfertwin.cps.opcua._discovery import Discovery

IDS = ("TU_A", "TU_B", "TU_C")  # TU_C learns of TU_B only by gossip


def _names(agent: Discovery) -> set[str]:
    return {p.asset_id for p in agent.peers.values()}


async def _until(agents, predicate, timeout=30.0):
    """Run explicit gossip rounds until `predicate()` holds (no sleeping)."""

    async def loop():
        while not predicate():
            for agent in agents:
                await agent.round()

    await asyncio.wait_for(loop(), timeout)


def test_join_spreads_and_leave_is_noticed(pki):
    descs = {d.asset_id: d for d in demo_descriptors()}
    cfg = pki.config()
    events: list[tuple[str, str, str]] = []

    def connector(me):
        # an asset registers itself with its own application certificate (a registration
        # naming another URI than the certificate's is refused)
        def open_session(url):
            return connect(url, url.rsplit("/", 1)[-1], **pki.client_kw(), certificate=me)

        return open_session

    async def scenario():
        servers = {}
        for aid in IDS:
            rep = build_representation(descs[aid])
            servers[aid] = await AssetServer(aid, rep.submodels, cfg).__aenter__()
        agents = {}
        for aid in IDS:

            def note(kind, peer, me=aid):
                events.append((me, kind, peer.asset_id))

            agents[aid] = Discovery(servers[aid], period_s=60.0, on_change=note)
            seeds = [] if aid == "TU_A" else [servers["TU_A"].endpoint]
            await agents[aid].join(seeds, connector(aid))

        everyone = set(IDS)

        def all_know_all() -> bool:
            return all(_names(a) == everyone - {i} for i, a in agents.items())

        await _until(agents.values(), all_know_all)

        # FindServers on any peer lists the others: there is no central registry.
        found = await agents["TU_B"]._ask(servers["TU_C"].endpoint)
        assert {p.asset_id for p in found} >= {"TU_A", "TU_B"}

        # TU_C leaves; every other asset notices.
        await agents.pop("TU_C").stop()
        await servers.pop("TU_C").__aexit__(None, None, None)
        await _until(agents.values(), lambda: all("TU_C" not in _names(a) for a in agents.values()))
        assert {me for me, kind, who in events if kind == "leave" and who == "TU_C"} == set(agents)
        for aid, agent in agents.items():
            await agent.stop()
            await servers[aid].__aexit__(None, None, None)

    asyncio.run(asyncio.wait_for(scenario(), timeout=120))
