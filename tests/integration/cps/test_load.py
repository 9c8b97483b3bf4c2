"""A bounded load test on loopback: 1,000 writes and 100 subscriptions, no lost update."""

from __future__ import annotations

import asyncio

from transfertwin.cps import AssetServer, ServerConfig, build_representation, connect
from transfertwin.cps.aas._demo import demo_descriptors
from transfertwin.cps.aas._representation import externally_synced
from transfertwin.cps.opcua._security import new_credentials

N_WRITES, N_SUBS = 1000, 100


def test_thousand_writes_and_hundred_subscriptions_lose_nothing(tmp_path):
    creds = new_credentials()
    desc = next(d for d in demo_descriptors() if d.asset_id == "TU_B")
    rep = build_representation(desc)
    writable = frozenset(("OperationalData", p) for p in externally_synced(rep))
    cfg = ServerConfig(cert_dir=tmp_path, credentials=creds)

    async def scenario():
        async with AssetServer("TU_B", rep.submodels, cfg, {}, writable) as server:
            kw = {"credentials": creds, "cert_dir": tmp_path}
            async with (
                connect(server.endpoint, "TU_B", role="viewer", **kw) as watcher,
                connect(server.endpoint, "TU_B", role="operator", **kw) as writer,
            ):
                final = f"o{N_WRITES - 1}"
                seen = [asyncio.Event() for _ in range(N_SUBS)]
                last: list[str | None] = [None] * N_SUBS

                class Handler:
                    def __init__(self, i: int) -> None:
                        self.i = i

                    def datachange_notification(self, node, val, data) -> None:
                        last[self.i] = val
                        if val == final:
                            seen[self.i].set()

                for i in range(N_SUBS):
                    await watcher.subscribe(Handler(i), ("OperationalData", "PossessedObjects"))
                for k in range(N_WRITES):
                    await writer.write("OperationalData", "PossessedObjects", f"o{k}")
                await asyncio.wait_for(asyncio.gather(*(e.wait() for e in seen)), 60)
                assert await server.get("OperationalData", "PossessedObjects") == final
                assert last == [final] * N_SUBS

    asyncio.run(asyncio.wait_for(scenario(), timeout=240))
