"""An operator who says where an object lies (`cps locate`) is believed everywhere: a module
whose own record still says it carries the object (a failed delivery it gave up on, and the
operator has taken the object off by hand) lets go of it, so the floor takes orders again
instead of refusing every one with "every transport module carries an object". Slow: the
demo floor in one process (~20 s)."""

from __future__ import annotations

import asyncio
import json

import pytest

from transfertwin.cps import LocalFloor, default_floor_spec
from transfertwin.cps.opcua import OperationRefused


@pytest.mark.slow
def test_locate_frees_the_module_that_still_carries_the_object(tmp_path, cps_certs):
    async def scenario():
        wd = cps_certs(tmp_path)
        async with LocalFloor(default_floor_spec(), wd, time_scale=0.0) as floor:
            graph = floor.nodes["KG"].role  # its last heartbeat of each asset: .info
            # what a delivery that failed and was given up leaves: o5 on TM_1, in TM_1's own
            # record and in the TMS's ledger
            assert await floor.nodes["TM_1"].role._set_possessed("o5")
            floor.nodes["TMS"].role.book.move("o5", "TM_1")
            loop = asyncio.get_running_loop()
            deadline = loop.time() + 30
            while "o5" not in graph.info.get("TM_1", {}).get("possesses", []):
                assert loop.time() < deadline, "the graph never heard TM_1 carries o5"
                await asyncio.sleep(0.1)
            async with floor.client("TMS") as tms:
                with pytest.raises(OperationRefused, match="TM_1 carries o5"):
                    await tms.call("OrderTo", "o2", "TU_C")  # the jam: nothing moves
                # the operator has put o5 on TU_A and says so
                assert await tms.call("Locate", "o5", "TU_A")
                async with floor.client("TM_1", role="viewer") as tm:
                    assert await tm.read("OperationalData", "PossessedObjects") == ""
                ledger = json.loads(await tms.call("Ledger"))
                assert ledger["locations"]["o5"] == "TU_A"
                deadline = loop.time() + 30
                while True:  # the graph hears the module's new record by its heartbeat
                    try:
                        op = await tms.call("OrderTo", "o2", "TU_C")
                        break
                    except OperationRefused as exc:
                        assert "carries" in exc.reason and loop.time() < deadline, exc.reason
                        await asyncio.sleep(0.2)
                assert op.startswith("op")

    asyncio.run(asyncio.wait_for(scenario(), timeout=240))
