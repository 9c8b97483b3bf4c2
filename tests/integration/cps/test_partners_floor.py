"""Plug and play by meaning (issue 39, item 5): a second make of transport module, of a class
the code has never seen and with a narrower object-mass range of its own, and a buffer
station, described only in the floor file (and so in their AAS and the knowledge graph).
The TMS finds the module by a capability query, orders use it, and an object heavier than
its constraint allows is refused up front. Slow: a small floor in one process (~20 s)."""

from __future__ import annotations

import asyncio
import json
import tomllib

import pytest

from transfertwin.cps import LocalFloor
from transfertwin.cps.floor import parse_floor
from transfertwin.cps.opcua import OperationRefused

# o33 weighs 2.84 kg, o1 4.52 kg (`transfertwin.objects.core_spec`)
FLOOR = """
name = "makes"
size_m = [12.0, 8.0]
logical = ["KG", "TMS"]

[[station]]
name = "A"
x_m = 2.6
y_m = 6.6
yaw_deg = 90.0
mount = "left"

[[station]]
name = "B"
x_m = 7.6
y_m = 6.6
yaw_deg = 90.0
mount = "right"
class = "buffer_station"

[[module]]
id = "LM_1"
x_m = 6.0
y_m = 5.2
class = "light_transport_module"

[module.constraints]
ObjectMassMax = 3.0

[[object]]
id = "o33"
at = "TU_A"

[[object]]
id = "o1"
at = "TU_A"

[operation]
policy = "nearest-idle"
"""


@pytest.mark.slow
def test_orders_use_a_module_class_the_code_has_never_seen_within_its_constraints(
        tmp_path, cps_certs):  # fmt: skip
    floor = parse_floor(tomllib.loads(FLOOR), "makes")

    async def scenario():
        wd = cps_certs(tmp_path)
        async with LocalFloor(floor, wd, time_scale=0.0) as local:
            kg = local.nodes["KG"].role.kg
            assert kg.query('SELECT ?c WHERE { ?a tt:assetId "LM_1" ; tt:assetClass ?c }') == [
                {"c": "light_transport_module"}]  # fmt: skip
            # the command line and the console pick units and modules by the class they run as
            info = {a["id"]: a for a in json.loads((wd / "cps.json").read_text())["assets"]}
            assert (info["TU_B"]["class"], info["TU_B"]["role_class"]) == (
                "buffer_station", "transfer_unit")  # fmt: skip
            assert info["LM_1"]["role_class"] == "transport_module"
            async with local.client("LM_1", role="viewer") as lm:
                assert await lm.read("Identification", "AssetClass") == "light_transport_module"
            async with local.client("TMS") as tms:
                with pytest.raises(OperationRefused, match="no online transport module carries o1"):
                    await tms.call("OrderTo", "o1", "TU_B")
                op = await tms.call("OrderTo", "o33", "TU_B")
                loop = asyncio.get_running_loop()
                deadline = loop.time() + 120
                while (status := json.loads(await tms.call("OperationStatus", op)))[
                        "state"] != "finished":  # fmt: skip
                    assert loop.time() < deadline, status
                    await asyncio.sleep(0.2)
                assert status["module"] == "LM_1", status
                assert status["result"]["status"] == "delivered", status
                ledger = json.loads(await tms.call("Ledger"))
                assert ledger["locations"]["o33"] == "TU_B"

    asyncio.run(asyncio.wait_for(scenario(), timeout=240))
