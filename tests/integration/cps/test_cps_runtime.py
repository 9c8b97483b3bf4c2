"""The demo CPS on loopback: a transport operation end to end over OPC UA, the experiment
manager against a unit's OPC UA interface, the knowledge graph following joins and leaves."""

from __future__ import annotations

import asyncio
import json

import pytest

from transfertwin.cps import Cps, CpsConfig
from transfertwin.study import ExperimentSpec, run_experiment


@pytest.mark.slow  # ~15-30 s (CI: the CPS slow group)
def test_demo_cps_end_to_end(tmp_path, cps_certs):
    async def scenario():
        # quiet gossip: the leave below is noticed in rounds the test runs itself
        async with Cps(CpsConfig(cps_certs(tmp_path), time_scale=0.0, gossip_period_s=10.0)) as cps:
            info = json.loads((tmp_path / "cps.json").read_text())
            assert {a["id"] for a in info["assets"]} >= {"TU_A", "TU_C", "TM_1", "TMS", "KG"}
            assert all(a["security_policy"] == "Basic256Sha256_SignAndEncrypt"
                       for a in info["assets"])  # fmt: skip
            assert (tmp_path / "credentials.json").stat().st_mode & 0o777 == 0o600
            kg = cps.kg
            assert kg.idle_transport_modules() == ["TM_1"]
            assert kg.virtual_models_of("TU_C_P") == ["TU_C"]
            assert "TU_C" in kg.receivers_at("C")

            # A transport operation through the TMS, over OPC UA, to its end.
            done = asyncio.Event()

            class Watch:
                def datachange_notification(self, node, val, data):
                    if val >= 1:
                        done.set()

            async with cps.client("TMS") as tms:
                await tms.subscribe(Watch(), ("OperationalData", "CompletedOperations"))
                op = await tms.call("SubmitTransportOperation", "TU_A", "TU_C", "o5")
                await asyncio.wait_for(done.wait(), timeout=240)
                assert await tms.read("OperationalData", "CompletedOperations") == 1
            record = cps.completed[0]
            assert record["operation"] == op and record["tm"] == "TM_1"
            assert record["result"]["y_pickup"] in (0, 1)
            # The object's location follows the outcome, everywhere it is kept.
            where = {"delivered": "TU_C", "failed at pick-up": "TU_A",
                     "failed at delivery": "TM_1"}[record["result"]["status"]]  # fmt: skip
            assert record["location"] == where == cps.ledger.location("o5")
            assert kg.locations()["o5"] == where
            async with cps.client("o5", role="viewer") as o5:
                assert await o5.read("OperationalData", "PossessedBy") == where
            if where != "TM_1":
                async with cps.client(where, role="viewer") as tu:
                    held = await tu.read("OperationalData", "PossessedObjects")
                    assert "o5" in held.split(",")
            assert kg.idle_transport_modules() == ["TM_1"]
            assert cps.ledger.moving() == {}

            # The experiment manager reaches the unit only through its OPC UA interface and
            # must reproduce the in-process record with the same seed.
            async with cps.client("EM") as em:
                remote = json.loads(
                    await em.call("RunExperiment", "TU_B", "o2", "front", "both", 30, 4)
                )
            local = run_experiment(
                ExperimentSpec("o2", "front", "both", 30, scene=cps.config.scene, seed=4)
            ).row()
            for key in ("y1", "y2", "success", "status", "t_end_1_s", "t_end_2_s",
                        "state_end_1", "state_end_2"):  # fmt: skip
                assert remote[key] == local[key], key

            # An asset that leaves is noticed by the graph (through the KG's discovery: its
            # gossip rounds, run here one after another instead of one per period).
            left = asyncio.Event()
            loop = asyncio.get_running_loop()
            cps.kg.subscribe(
                lambda kind, aid: (
                    aid == "TU_D" and kind == "leave" and loop.call_soon_threadsafe(left.set)
                )
            )
            assert "TU_D" in cps.kg.receivers_at("D")
            await cps.leave("TU_D")

            async def rounds() -> None:
                while not left.is_set():
                    await cps.assets["KG"].discovery.round()
                    await asyncio.sleep(0)  # let the graph's callback in

            await asyncio.wait_for(rounds(), timeout=60)
            assert "TU_D" not in cps.kg.receivers_at("D")
            status = {a["id"]: a["status"] for a in cps.kg.assets()}
            assert status.get("TU_D") in (None, "offline")

    asyncio.run(asyncio.wait_for(scenario(), timeout=300))
