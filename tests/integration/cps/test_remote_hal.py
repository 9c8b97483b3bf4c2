"""A transfer unit on real hardware: its asset process reaches the machine through a HAL
gateway over OPC UA (``[hal] kind = "remote"``). Here a real asyncua server on loopback
plays the gateway: the unit's belt commands must arrive there as written values, and what
the gateway's barriers say must appear on the unit's own server, which nobody else may
overwrite."""

from __future__ import annotations

import asyncio
import time
from pathlib import Path

import pytest
from asyncua import ua

from tests.integration.cps._plant_gateway import PlantGateway
from transfertwin.cps import (
    AssetConfig,
    HalConfig,
    asset_node,
    connect,
    default_floor_spec,
    floor_toml,
)
from transfertwin.cps.opcua import free_port


def _unit_config(tmp_path: Path, gateway_port: int) -> AssetConfig:
    text = floor_toml(default_floor_spec()).replace(
        'mount = "left"', f'mount = "left"\nhal = "remote"\n'
        f'gateway = "opc.tcp://127.0.0.1:{gateway_port}/gateway"', 1)  # fmt: skip
    (tmp_path / "floor.toml").write_text(text)
    hal = HalConfig("remote", endpoint=f"opc.tcp://127.0.0.1:{gateway_port}/gateway",
                    insecure=True, poll_s=0.02)  # fmt: skip
    return AssetConfig(asset_id="TU_A", floor_file=tmp_path / "floor.toml", host="127.0.0.1",
                       port=free_port(), seeds=(), cert_dir=tmp_path / "certs",
                       trust_dir=tmp_path / "trusted", credentials_file=None,
                       state_dir=tmp_path / "state", insecure=True, hal=hal)  # fmt: skip


async def _until(check, timeout_s: float = 3.0) -> float:
    t0 = time.monotonic()
    while not await check():
        assert time.monotonic() - t0 < timeout_s, "not within the time"
        await asyncio.sleep(0.02)
    return time.monotonic() - t0


def test_a_remote_unit_drives_its_belts_and_reads_its_barriers_at_the_gateway(tmp_path):
    port = free_port()
    cfg = _unit_config(tmp_path, port)

    # a PLC's server: two belt setpoints, two light barriers (and a module's nodes, unused)
    gateway = PlantGateway(port, "TM_1", {"TU_A": "A"}, "o1", at="TU_A", seed=0).start()

    async def scenario() -> None:
        try:
            async with asset_node(cfg) as node, connect(node.server.endpoint, "TU_A",
                                                       credentials=None, insecure=True) as tu:
                # a belt command reaches the hardware, and the unit publishes it
                assert await tu.call("SetBeltSpeed", "left", 0.25) is True
                assert gateway.value("TU_A.BeltSpeedLeft") == pytest.approx(0.25)
                assert gateway.value("TU_A.BeltSpeedRight") == 0.0
                assert await tu.read("OperationalData", "BeltSpeedLeft") == pytest.approx(0.25)
                # the machine's barrier is seen on the unit's server within a few polls
                assert await tu.read("OperationalData", "BarrierNearInterrupted") is False
                gateway.set("TU_A.BarrierNear", True)

                async def near() -> bool:
                    return await tu.read("OperationalData", "BarrierNearInterrupted") is True

                assert await _until(near) < 1.0
                assert await tu.read("OperationalData", "BarrierFarInterrupted") is False
                # a module's simulation may not overwrite a real barrier
                with pytest.raises(ua.UaStatusCodeError):
                    await tu.write("OperationalData", "BarrierNearInterrupted", False)
                assert await tu.read("OperationalData", "BarrierNearInterrupted") is True
                gateway.set("TU_A.BarrierNear", False)

                async def clear() -> bool:
                    return await tu.read("OperationalData", "BarrierNearInterrupted") is False

                await _until(clear)
                # the gateway away: a belt command is refused, not silently taken (stopped
                # off this loop: its server closes the unit's session, which this loop serves)
                await asyncio.to_thread(gateway.stop)
                with pytest.raises(ua.UaStatusCodeError):
                    await tu.call("SetBeltSpeed", "right", 0.1)
                assert await tu.read("OperationalData", "BeltSpeedRight") == 0.0
        finally:
            gateway.stop()

    asyncio.run(scenario())
