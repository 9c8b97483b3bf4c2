"""An asset's session with its HAL gateway is secure (Basic256Sha256, SignAndEncrypt, with
certificates both ways), against a real secure asyncua gateway: the gateway's certificate
must be on the asset's gateway trust list, the asset's on the gateway's; a gateway that
offers NoSecurity only is refused unless ``[hal] insecure = true``. Each refusal is one
clear error, said once by a unit that keeps trying, and a unit that is told to trust the
gateway's certificate connects without a restart."""

from __future__ import annotations

import asyncio
import dataclasses
import logging
import shutil
import time
from pathlib import Path

import pytest
from asyncua import ua

from tests.integration.cps._plant_gateway import PlantGateway
from transfertwin.cli import main
from transfertwin.cps import (
    AssetConfig,
    GatewayHAL,
    HalConfig,
    asset_node,
    connect,
    write_asset_config,
)
from transfertwin.cps.opcua import ensure_certificate, free_port, trust_certificate

UNITS = {"TU_A": "A"}


@pytest.fixture(scope="module")
def gateway(tmp_path_factory, pki):
    """A secure gateway (its own certificate) that trusts the test run's asset certificate
    (``client-operator`` in the shared cert folder)."""
    base = tmp_path_factory.mktemp("gw")
    cert, key = asyncio.run(ensure_certificate(base / "certs", "gateway"))
    trust_certificate(base / "trusted", pki.cert_dir / "client-operator.der")
    plant = PlantGateway(free_port(), "TM_1", UNITS, "o2", at="TU_A", seed=0,
                         secure=(cert, key, base / "trusted")).start()  # fmt: skip
    yield plant, cert
    plant.stop()


def _cfg(tmp_path: Path, pki, endpoint: str, **hal) -> AssetConfig:
    (tmp_path / "floor.toml").write_text(_floor(endpoint))
    return AssetConfig(asset_id="TU_A", floor_file=tmp_path / "floor.toml", host="127.0.0.1",
                       port=free_port(), seeds=(), cert_dir=pki.cert_dir,
                       trust_dir=tmp_path / "trusted", credentials_file=None,
                       state_dir=tmp_path / "state", insecure=True,
                       hal=HalConfig("remote", endpoint=endpoint, poll_s=0.02,
                                     **hal))  # fmt: skip


def _floor(endpoint: str) -> str:
    from transfertwin.cps import default_floor_spec, floor_toml

    return floor_toml(default_floor_spec()).replace(
        'mount = "left"', f'mount = "left"\nhal = "remote"\ngateway = "{endpoint}"', 1)


def test_a_unit_drives_a_secure_gateway_it_trusts(tmp_path, pki, gateway):
    plant, cert = gateway
    trust_certificate(tmp_path / "gateways", cert)
    cfg = _cfg(tmp_path, pki, plant.url, trust_dir=tmp_path / "gateways")

    async def scenario() -> tuple[object, dict[str, bool]]:
        hal = GatewayHAL(cfg)
        try:
            await hal.set_belt("left", 0.2)
            policy = hal.link.client.security_policy
            plant.set("TU_A.BarrierFar", True)
            return (policy.URI, policy.Mode), await hal.barriers()
        finally:
            await hal.close()

    (uri, mode), barriers = asyncio.run(scenario())
    assert uri.endswith("#Basic256Sha256") and mode == ua.MessageSecurityMode.SignAndEncrypt
    assert plant.value("TU_A.BeltSpeedLeft") == pytest.approx(0.2)
    assert barriers == {"near": False, "far": True}
    plant.set("TU_A.BarrierFar", False)


def test_an_untrusted_gateway_is_refused_once_and_trusted_later_without_a_restart(
    tmp_path, pki, gateway, caplog
):
    plant, cert = gateway
    folder = tmp_path / "gateways"  # empty: nothing trusted yet
    cfg = _cfg(tmp_path, pki, plant.url, trust_dir=folder)
    caplog.set_level(logging.INFO, logger="transfertwin.cps")

    async def scenario() -> tuple[str, float]:
        async with asset_node(cfg) as node, connect(node.server.endpoint, "TU_A",
                                                   credentials=None, insecure=True) as tu:
            with pytest.raises(ua.UaStatusCodeError):  # refused, not silently taken
                await tu.call("SetBeltSpeed", "right", 0.1)
            await asyncio.sleep(0.3)  # many polls: the refusal is said once
            said = [r.getMessage() for r in caplog.records
                    if r.levelno >= logging.WARNING and r.name.startswith("transfertwin")]
            trust_certificate(folder, cert)  # the engineer trusts it; no restart
            plant.set("TU_A.BarrierNear", True)
            t0 = time.monotonic()
            while await tu.read("OperationalData", "BarrierNearInterrupted") is not True:
                assert time.monotonic() - t0 < 5, "the trusted gateway was not reached"
                await asyncio.sleep(0.05)
            assert await tu.call("SetBeltSpeed", "right", 0.1) is True
            return said, time.monotonic() - t0

    said, _ = asyncio.run(scenario())
    plant.set("TU_A.BarrierNear", False)
    assert len(said) == 1, said
    assert "its certificate (" in said[0] and f"is not trusted; put it in {folder}" in said[0]
    assert plant.value("TU_A.BeltSpeedRight") == pytest.approx(0.1)


def test_a_gateway_that_does_not_trust_the_asset_is_one_clear_error(tmp_path, gateway):
    plant, cert = gateway
    trust_certificate(tmp_path / "gateways", cert)
    cfg = AssetConfig(asset_id="TU_A", floor_file=tmp_path / "floor.toml", host="127.0.0.1",
                      port=free_port(), seeds=(), cert_dir=tmp_path / "own-certs",
                      trust_dir=tmp_path / "trusted", credentials_file=None,
                      state_dir=tmp_path / "state", insecure=True,
                      hal=HalConfig("remote", endpoint=plant.url,
                                    trust_dir=tmp_path / "gateways"))  # fmt: skip

    async def scenario() -> None:
        hal = GatewayHAL(cfg)  # a certificate of its own, made now: the gateway lacks it
        try:
            await hal.set_belt("left", 0.3)
        finally:
            await hal.close()

    with pytest.raises(ua.UaStatusCodeError, match=r"does not trust this asset's certificate; "
                                                   r"trust .*own-certs/client-operator\.der at "
                                                   r"the gateway"):  # fmt: skip
        asyncio.run(scenario())
    assert plant.value("TU_A.BeltSpeedLeft") != pytest.approx(0.3)


def test_a_gateway_without_security_needs_insecure_explicitly(tmp_path, pki):
    plant = PlantGateway(free_port(), "TM_1", UNITS, "o2", at="TU_A", seed=0).start()
    try:
        async def use(cfg) -> dict[str, bool]:
            hal = GatewayHAL(cfg)
            try:
                return await hal.barriers()
            finally:
                await hal.close()

        with pytest.raises(ConnectionError, match="offers no Basic256Sha256 SignAndEncrypt "
                                                  r"endpoint \(it offers None\); NoSecurity "
                                                  "needs .hal. insecure = true"):  # fmt: skip
            asyncio.run(use(_cfg(tmp_path, pki, plant.url)))
        explicit = _cfg(tmp_path, pki, plant.url, insecure=True)
        assert asyncio.run(use(explicit)) == {"near": False, "far": False}
    finally:
        plant.stop()


def _workdir(tmp_path: Path, pki, endpoint: str) -> tuple[Path, AssetConfig]:
    """A floor's workdir as `cps up` leaves it (``certs/``, ``assets/<id>/asset.toml``): TU_A on
    real hardware behind `endpoint` with the default gateway trust list (its own copy of
    the run's certificates), TU_B virtual."""
    wd = tmp_path / "w"
    (wd / "certs" / "trusted").mkdir(parents=True)
    certs = shutil.copytree(pki.cert_dir, wd / "assets" / "TU_A" / "certs")
    cfg = dataclasses.replace(_cfg(tmp_path, pki, endpoint), cert_dir=certs,
                              trust_dir=wd / "assets" / "TU_A" / "trusted")  # fmt: skip
    write_asset_config(wd / "assets" / "TU_A" / "asset.toml", cfg)
    write_asset_config(wd / "assets" / "TU_B" / "asset.toml",
                       dataclasses.replace(cfg, asset_id="TU_B", hal=HalConfig()))
    return wd, cfg


def _tree(root: Path) -> dict[str, bytes]:
    return {str(p.relative_to(root)): p.read_bytes() for p in root.rglob("*") if p.is_file()}


def test_cps_trust_gateway_puts_the_gateways_certificate_on_one_assets_hal_list(
    tmp_path, pki, gateway, capsys
):
    plant, cert = gateway
    wd, cfg = _workdir(tmp_path, pki, plant.url)

    async def belt(speed: float) -> None:
        hal = GatewayHAL(cfg)
        try:
            await hal.set_belt("left", speed)
        finally:
            await hal.close()

    with pytest.raises(ua.UaStatusCodeError, match=r"is not trusted; put it in .*gateways"):
        asyncio.run(belt(0.4))
    before = _tree(wd)
    argv = ["cps", "trust", str(cert), "--workdir", str(wd), "--asset", "TU_A", "--gateway"]
    assert main(argv) == 0
    out = capsys.readouterr().out
    assert out.startswith(f"trusted HAL gateway {plant.url} for TU_A: CN=gateway")
    added = set(_tree(wd)) - set(before)
    # on TU_A's gateway list only (cert_dir/gateways), not on any list of clients
    assert len(added) == 1 and next(iter(added)).startswith("assets/TU_A/certs/gateways/")
    asyncio.run(belt(0.4))  # the asset now opens the secure session
    assert plant.value("TU_A.BeltSpeedLeft") == pytest.approx(0.4)
    plant.set("TU_A.BeltSpeedLeft", 0.0)
    assert main(argv) == 0 and _tree(wd).keys() == (before.keys() | added)  # again: no-op


@pytest.mark.parametrize(("case", "extra", "says"), [
    ("no asset named", ["--gateway"], "name it with --asset ID"),
    ("no such asset", ["--asset", "TU_X", "--gateway"], "no such asset file"),
    ("a path for an asset", ["--asset", "../TU_A", "--gateway"], "no such asset file"),
    ("a virtual asset", ["--asset", "TU_B", "--gateway"], 'not "remote": it has no HAL gateway'),
    ("the asset's own certificate", ["--asset", "TU_A", "--gateway", "OWN"],
     "TU_A's own certificate; trust the one the gateway"),
])  # fmt: skip
def test_cps_trust_gateway_refuses_bad_input_with_one_line(case, extra, says, tmp_path, pki,
                                                           gateway, capfd):  # fmt: skip
    plant, cert = gateway
    wd, cfg = _workdir(tmp_path, pki, plant.url)
    if "OWN" in extra:
        extra, cert = extra[:-1], cfg.cert_dir / "client-operator.der"
    before = _tree(tmp_path)
    assert main(["cps", "trust", str(cert), "--workdir", str(wd), *extra]) == 2, case
    err = capfd.readouterr().err
    assert err.count("\n") == 1 and err.startswith("transfertwin: error: ") and says in err, err
    assert _tree(tmp_path) == before, f"{case}: something was written"
