"""The demo floor in one process (`LocalFloor`: the same asset nodes and roles as a floor of
processes, in one event loop) on loopback: a transport operation end to end over OPC UA,
the experiment manager against a unit's OPC UA interface, the knowledge graph following
joins and leaves."""

from __future__ import annotations

import asyncio
import json

import pytest

from transfertwin.cps import LocalFloor, default_floor_spec
from transfertwin.cps.hal import load_scene
from transfertwin.study import ExperimentSpec, run_experiment


async def _until(check, timeout_s: float = 30.0) -> None:
    """Wait until `check()` holds (the graph and the publications follow by heartbeats)."""
    loop = asyncio.get_running_loop()
    deadline = loop.time() + timeout_s
    while not check():
        assert loop.time() < deadline, "not within the time"
        await asyncio.sleep(0.1)


@pytest.mark.slow  # ~15-30 s (CI: the CPS slow group)
def test_demo_cps_end_to_end(tmp_path, cps_certs):
    async def scenario():
        wd = cps_certs(tmp_path)
        async with LocalFloor(default_floor_spec(), wd, time_scale=0.0) as floor:
            info = json.loads((wd / "cps.json").read_text())
            assert {a["id"] for a in info["assets"]} >= {"TU_A", "TU_C", "TM_1", "TMS", "KG"}
            assert all(a["security_policy"] == "Basic256Sha256_SignAndEncrypt"
                       for a in info["assets"])  # fmt: skip
            assert (wd / "credentials.json").stat().st_mode & 0o777 == 0o600
            kg = floor.nodes["KG"].role.kg
            await _until(lambda: kg.idle_transport_modules() == ["TM_1"])
            assert kg.virtual_models_of("TU_C_P") == ["TU_C"]
            assert "TU_C" in kg.receivers_at("C")

            # A transport operation through the TMS, over OPC UA, to its end.
            done = asyncio.Event()

            class Watch:
                def datachange_notification(self, node, val, data):
                    if val >= 1:
                        done.set()

            async with floor.client("TMS") as tms:
                await tms.subscribe(Watch(), ("OperationalData", "CompletedOperations"))
                op = await tms.call("SubmitTransportOperation", "TU_A", "TU_C", "o5")
                await asyncio.wait_for(done.wait(), timeout=240)
                assert await tms.read("OperationalData", "CompletedOperations") == 1
                record = json.loads(await tms.call("OperationStatus", op))
                ledger = json.loads(await tms.call("Ledger"))
            assert record["operation"] == op and record["module"] == "TM_1"
            assert record["result"]["y_pickup"] in (0, 1)
            # The object's location follows the outcome, everywhere it is kept.
            where = record["location"]
            assert where in ("TU_A", "TU_C", "TM_1"), where
            assert (where == "TU_C") == (record["result"]["status"] == "delivered")
            assert ledger["locations"]["o5"] == where and ledger["moving"] == {}
            await _until(lambda: kg.locations().get("o5") == where)
            async with floor.client("o5", role="viewer") as o5:
                for _ in range(100):  # the TMS publishes the ledger within a second
                    if await o5.read("OperationalData", "PossessedBy") == where:
                        break
                    await asyncio.sleep(0.1)
                assert await o5.read("OperationalData", "PossessedBy") == where
            if where != "TM_1":
                async with floor.client(where, role="viewer") as tu:
                    held = await tu.read("OperationalData", "PossessedObjects")
                    assert "o5" in held.split(",")
            await _until(lambda: kg.idle_transport_modules() == ["TM_1"])

            # The experiment manager reaches the unit only through its OPC UA interface and
            # must reproduce the in-process record with the same seed.
            async with floor.client("EM") as em:
                remote = json.loads(
                    await em.call("RunExperiment", "TU_B", "o2", "front", "both", 30, 4)
                )
            local = run_experiment(
                ExperimentSpec("o2", "front", "both", 30, scene=load_scene(), seed=4)
            ).row()
            for key in ("y1", "y2", "success", "status", "t_end_1_s", "t_end_2_s",
                        "state_end_1", "state_end_2"):  # fmt: skip
                assert remote[key] == local[key], key

            # An asset that leaves is noticed by the graph (it announces its leave).
            assert "TU_D" in kg.receivers_at("D")
            await floor.stop("TU_D")
            await _until(lambda: "TU_D" not in kg.receivers_at("D"), 60)
            status = {a["id"]: a["status"] for a in kg.assets()}
            assert status.get("TU_D") in (None, "offline")

    asyncio.run(asyncio.wait_for(scenario(), timeout=300))
