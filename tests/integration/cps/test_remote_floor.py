"""A floor with its machines on real hardware, deployed as a plant engineer would: a floor
file whose two stations and transport module say ``hal = "remote"`` and name their HAL
gateway, `cps up --floor` (one process per asset, secure), the gateway's certificate
trusted per asset with `cps trust --asset ID --gateway` and the assets' certificates at the
gateway, then an order from the command line carried out by the machines. The gateway is
the real asyncua server of `_plant_gateway` whose nodes a MuJoCo transfer system drives in
real time. Slow: a floor of processes and real-time transfers, ~60 s."""

from __future__ import annotations

import asyncio
import dataclasses
import json
import time

import pytest

from tests.integration.cps._cli import run_main, tt
from tests.integration.cps._plant_gateway import PlantGateway
from transfertwin.cps import default_floor_spec, floor_toml
from transfertwin.cps.opcua import ensure_certificate, free_port, trust_certificate

UNITS = {"TU_A": "A", "TU_B": "B"}


def _floor(gateway: str) -> str:
    """The demonstration floor's stations A and B and TM_1 on the gateway's machines (the
    plant behind it has the same floor), o2 on TU_B, the knowledge graph and the TMS."""
    spec = default_floor_spec()
    stations = tuple(dataclasses.replace(s, hal="remote", gateway=gateway)
                     for s in spec.stations if s.unit in UNITS)  # fmt: skip
    modules = (dataclasses.replace(spec.modules[0], hal="remote", gateway=gateway),)
    return floor_toml(dataclasses.replace(spec, name="remote-floor", stations=stations,
                                          modules=modules, objects=(("o2", "TU_B"),),
                                          logical=("KG", "TMS")))  # fmt: skip


@pytest.mark.slow
def test_a_floor_of_remote_machines_runs_an_order_after_cps_up_and_cps_trust(tmp_path, capfd):
    gw = tmp_path / "gateway"
    cert, key = asyncio.run(ensure_certificate(gw / "certs", "gateway"))
    plant = PlantGateway(free_port(), "TM_1", UNITS, "o2", at="TU_B", seed=5,
                         secure=(cert, key, gw / "trusted")).start()  # fmt: skip
    (tmp_path / "floor.toml").write_text(_floor(plant.url))
    wd = tmp_path / "w"
    try:
        up = tt("cps", "up", "--policy", "nearest-idle",
                "--floor", str(tmp_path / "floor.toml"), "--workdir", str(wd),
                "--detach", "--lease", "2", timeout=240)  # fmt: skip
        assert up.returncode == 0, up.stderr
        for aid in (*UNITS, "TM_1"):
            files = (wd / "assets" / aid / "asset.toml").read_text()
            assert 'kind = "remote"' in files and plant.url in files
            # each machine's asset trusts this gateway, and the gateway trusts each asset
            trusted = run_main(capfd, "cps", "trust", str(cert), "--workdir", str(wd),
                               "--asset", aid, "--gateway")  # fmt: skip
            assert trusted.returncode == 0, trusted.stderr
            # the asset makes its gateway client certificate on its first try to connect
            own = wd / "assets" / aid / "certs" / "client-operator.der"
            t0 = time.monotonic()
            while not own.is_file():
                assert time.monotonic() - t0 < 30, f"{aid} made no gateway client certificate"
                time.sleep(0.2)
            trust_certificate(gw / "trusted", own)
        t0 = time.monotonic()  # the units say the refusal once and keep trying: no restart
        while not _connected(wd):
            assert time.monotonic() - t0 < 30, "the assets did not reach their gateway"
            time.sleep(0.2)
        order = run_main(capfd, "cps", "order", "--workdir", str(wd), "--object", "o2", "--to",
                         "TU_A", "--timeout", "120")  # fmt: skip
        status = run_main(capfd, "cps", "status", "--workdir", str(wd), "--json")
    finally:
        down = tt("cps", "down", "--workdir", str(wd), timeout=120) if wd.exists() else None
        plant.stop()
    assert order.returncode == 0, order.stdout + order.stderr
    assert "o2 is at TU_A" in order.stdout
    assert plant.holder == "TU_A"  # the physics behind the gateway agrees
    assert plant.log.commands == ["navigate B", "dock B", "undock", "navigate A", "dock A",
                                  "undock"]  # fmt: skip
    for asset in ("TM_1", "TU_A", "TU_B"):  # every belt ran at the gateway
        assert plant.log.belts[f"{asset}.BeltSpeedLeft"] == pytest.approx(0.15)
    doc = json.loads(status.stdout)
    assert doc["objects"]["o2"]["location"] == "TU_A"
    remote = {a["id"] for a in doc["assets"] if '"hal": "remote"' in json.dumps(a)}
    assert remote == {*UNITS, "TM_1"}, doc["assets"]
    assert down is not None and down.returncode == 0, down.stderr


def _connected(wd) -> bool:
    """Whether every remote asset's log says its gateway session is open."""
    return all("connected (Basic256Sha256" in (wd / "logs" / f"{aid}.log").read_text()
               for aid in (*UNITS, "TM_1"))
