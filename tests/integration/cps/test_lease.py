"""Leases that stay cheap as a floor grows (issue 27, item 5), with real asset nodes in this
process on loopback: an idle asset renews its lease with a renewal, not its description;
a change of its live state sends the description again; the directory travels only when
it changed; a restarted graph refuses the renewals of leases it does not hold, and the
assets' descriptions rebuild it within a heartbeat period; a graph that did not run for
longer than a lease expires nobody for it; an asset that stops beating is offline within
its lease; one that stops cleanly leaves and stays gone."""

from __future__ import annotations

import asyncio
import dataclasses
import time

from tests.integration.cps._cli import two_module_floor

LEASE_S = 1.5


def test_idle_assets_renew_and_a_restarted_graph_gets_their_descriptions(tmp_path):
    from transfertwin.cps import asset_node, load_floor, prepare_floor
    from transfertwin.cps.opcua import connect

    (tmp_path / "floor.toml").write_text(two_module_floor("lease", {"o1": "TU_A"}))
    spec = load_floor(tmp_path / "floor.toml")
    configs = prepare_floor(spec, tmp_path / "w", insecure=True, lease_s=LEASE_S)
    kg_url = configs["KG"].endpoint
    cfg = {a: dataclasses.replace(configs[a], seeds=(kg_url,)) for a in ("KG", "o1", "TU_A")}
    cfg["KG"] = dataclasses.replace(cfg["KG"], seeds=())

    async def until(check, timeout_s: float, what: str) -> float:
        t0 = time.monotonic()
        while not check():
            assert time.monotonic() - t0 < timeout_s, f"{what} not within {timeout_s} s"
            await asyncio.sleep(0.05)
        return time.monotonic() - t0

    async def main():
        kg = await asset_node(cfg["KG"]).__aenter__()
        try:
            async with asset_node(cfg["o1"]) as o1, asset_node(cfg["TU_A"]) as tu:
                graph = kg.role
                await until(lambda: {"o1", "TU_A"} <= set(graph.leases), 10.0, "both joined")
                full = graph.beats["full"]
                await asyncio.sleep(4 * LEASE_S / 3)  # four heartbeat periods, idle
                idle = dict(graph.beats)
                assert idle["full"] == full and idle["renewals"] >= 4, idle  # renewals only
                assert o1.lease.directory.endswith(f".{graph._directory}")
                assert o1._known["TU_A"] == tu.server.endpoint  # the directory reached it
                # a live change (a client writes where o1 lies) goes out in full
                async with connect(o1.server.endpoint, "o1", credentials=None,
                                   insecure=True) as c:  # fmt: skip
                    await c.write("OperationalData", "PossessedBy", "TM_1")
                await until(lambda: graph.info["o1"].get("location") == "TM_1", 3 * LEASE_S,
                            "o1's new location")  # fmt: skip
                assert graph.beats["full"] == full + 1
                # the graph restarts: it holds no lease, refuses renewals, gets descriptions
                await kg.__aexit__(None, None, None)
                kg = await asset_node(cfg["KG"]).__aenter__()
                t = await until(lambda: {"o1", "TU_A"} <= set(kg.role.leases), 10.0,
                                "both back in the restarted graph")  # fmt: skip
                assert kg.role.info["o1"]["location"] == "TM_1"  # from o1's description
                assert kg.role.beats["refused"] >= 1 and kg.role.beats["full"] >= 2
                assert t < 4 * LEASE_S, t
                # the graph does not run for longer than a lease (here the whole process
                # stalls): that time is not the assets' silence, nobody lapses
                refused = kg.role.beats["refused"]
                time.sleep(2 * LEASE_S)
                await asyncio.sleep(0.3)
                assert {"o1", "TU_A"} <= set(kg.role.leases), kg.role.gone
                assert kg.role.beats["refused"] == refused  # no lapse (and no rejoin) for it
                assert kg.role.stalled_s >= 2 * LEASE_S - 0.3
                # o1 stops beating (its host hangs): offline within its lease (plus the time
                # the graph itself did not run)
                for task in list(o1._tasks):
                    task.cancel()
                t0, stalled = time.monotonic(), kg.role.stalled_s
                await until(lambda: "o1" not in kg.role.leases, 4 * LEASE_S, "o1 lapsed")
                assert kg.role.gone["o1"]["reason"] == "lapsed"
                assert time.monotonic() - t0 <= LEASE_S + 1.0 + kg.role.stalled_s - stalled
            # TU_A stopped cleanly: it left, and no heartbeat after its leave joined it again
            await asyncio.sleep(LEASE_S)
            assert "TU_A" not in kg.role.leases and kg.role.gone["TU_A"]["reason"] == "left"
            return dict(kg.role.beats)
        finally:
            await kg.__aexit__(None, None, None)

    beats = asyncio.run(asyncio.wait_for(main(), 120))
    assert beats["renewals"] >= 1, beats  # renewing again after the descriptions


def test_a_lease_is_held_by_one_start_of_the_process_not_by_its_pid(tmp_path):
    """Two processes of one asset on two hosts may have the same pid: the graph keys the lease
    on the start's random instance id, so the other process's renewal is refused (it must
    send its description) even with the pid of the one holding the lease."""
    import json
    import os

    from transfertwin.cps import asset_node, load_floor, prepare_floor
    from transfertwin.cps.node import heartbeat_payload
    from transfertwin.cps.opcua import OperationRefused, connect

    (tmp_path / "floor.toml").write_text(two_module_floor("instances", {"o1": "TU_A"}))
    spec = load_floor(tmp_path / "floor.toml")
    configs = prepare_floor(spec, tmp_path / "w", insecure=True, lease_s=30.0)
    kg_cfg = dataclasses.replace(configs["KG"], seeds=())
    desc = {d.asset_id: d for d in spec.descriptors()}["TU_A"]
    full = heartbeat_payload(desc, configs["TU_A"].endpoint, "None", {"state": "idle"}, "a1")

    def renewal(instance: str) -> str:
        return json.dumps({"id": "TU_A", "instance": instance, "pid": os.getpid(),
                           "renew": True, "directory": ""})  # fmt: skip

    async def main() -> str:
        async with asset_node(kg_cfg) as kg, connect(kg_cfg.endpoint, "KG", credentials=None,
                                                     insecure=True) as c:  # fmt: skip
            await c.call("Heartbeat", full)
            await c.call("Heartbeat", renewal("a1"))  # the holder renews
            assert kg.role.info["TU_A"]["instance"] == "a1"
            try:
                await c.call("Heartbeat", renewal("b2"))  # same asset, same pid, other start
            except OperationRefused as exc:
                return exc.status
            return "accepted"

    assert asyncio.run(asyncio.wait_for(main(), 60)) == "BadNotFound"
