"""The DT network with one process per asset (issue: the floor on a shop floor): a floor of
two transport modules as separate processes on their own loopback addresses; a unit killed
with -9 is seen offline, restarted by hand and seen again; a module on standby joins at
runtime and is given work; a module killed in the middle of an operation loses nothing."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from tests.integration.cps._cli import tt, two_module_floor

FLOOR = two_module_floor("two-modules", {"o1": "TU_A", "o2": "TU_B"})

LEASE_S = 2.0


def status(wd: Path) -> dict:
    from transfertwin.cli._cps_floor import floor_status

    return floor_status(wd)


def wait_for(wd: Path, check, timeout_s: float, what: str) -> tuple[dict, float]:
    """Poll the floor's status until `check(doc)` holds; returns it and the time taken."""
    t0 = time.monotonic()
    last: dict | None = None
    while time.monotonic() - t0 < timeout_s:
        try:
            last = status(wd)
            if check(last):
                return last, time.monotonic() - t0
        except Exception:  # the graph restarting: try again
            pass
        time.sleep(0.2)
    raise AssertionError(f"{what} not within {timeout_s} s; last status: {last}")


def asset(doc: dict, aid: str) -> dict:
    return next(a for a in doc["assets"] if a["id"] == aid)


STARTED: list[subprocess.Popen] = []  # by the tests: stopped at the end whatever happened


def start(wd: Path, aid: str) -> subprocess.Popen:
    log = (wd / "logs" / f"{aid}.log").open("ab")
    proc = subprocess.Popen(
        [sys.executable, "-m", "transfertwin", "cps", "asset", "--config",
         str(wd / "assets" / f"{aid}.toml")], stdout=log, stderr=subprocess.STDOUT,
        start_new_session=True)  # fmt: skip
    STARTED.append(proc)
    return proc


def module_at_work(wd: Path, obj: str, timeout_s: float = 60.0) -> dict:
    """The module the TMS assigned the running operation for `obj`, once it has started
    (from the TMS's ledger: the graph's view of a module's state lags by a heartbeat)."""
    import asyncio

    from transfertwin.cli._cps_floor import _call, _info

    info, creds = _info(wd)
    t0 = time.monotonic()
    while time.monotonic() - t0 < timeout_s:
        ledger = json.loads(asyncio.run(_call(info, creds, "TMS", "Ledger")))
        for op in ledger["operations"]:
            if (op["object"] == obj and op["state"] == "running"
                    and op["phase"] in ("navigating", "docking", "scanning", "transferring")):
                return asset(status(wd), op["module"])
        time.sleep(0.1)
    raise AssertionError(f"no operation for {obj} started within {timeout_s} s")


def objects_consistent(doc: dict) -> None:
    """Every object is in the ledger once, at an asset of the floor or unknown with where it
    was last seen."""
    assert set(doc["objects"]) == {"o1", "o2"}
    holders = {"TU_A", "TU_B", "TM_1", "TM_2"}
    for o, v in doc["objects"].items():
        if v["unknown"]:
            assert v["last_seen"] in holders and v["operation"].startswith("op"), (o, v)
        else:
            assert v["location"] in holders, (o, v)


@pytest.fixture(scope="module")
def floor(tmp_path_factory):
    base = tmp_path_factory.mktemp("floor")
    (base / "floor.toml").write_text(FLOOR)
    wd = base / "w"
    # in real time, so that a kill lands in the middle of an operation
    up = tt("cps", "up", "--floor", str(base / "floor.toml"), "--workdir", str(wd), "--detach",
            "--time-scale", "1", "--lease", str(LEASE_S), "--start-timeout", "150", timeout=200)
    assert up.returncode == 0, up.stderr
    assert "7 asset processes" in up.stdout and "1 on standby" in up.stdout
    try:
        yield wd
    finally:
        down = tt("cps", "down", "--workdir", str(wd))
        for proc in STARTED:
            if proc.poll() is None:
                proc.kill()
    assert down.returncode == 0 and "killed" not in down.stdout, down.stdout + down.stderr


def test_every_asset_is_its_own_process_on_its_own_address(floor):
    doc = status(floor)
    online = {a["id"]: a for a in doc["assets"] if a["online"]}
    assert set(online) == {"KG", "TMS", "TU_A", "TU_B", "TM_1", "o1", "o2"}
    assert len({a["pid"] for a in online.values()}) == 7
    hosts = {a["address"].split("//")[1].split(":")[0] for a in online.values()}
    assert len(hosts) == 7 and all(h.startswith("127.") for h in hosts)
    assert all(a["address"].startswith("opc.tcp://") for a in online.values())
    assert doc["objects"]["o1"] == {"location": "TU_A", "unknown": False, "moving": None}
    # each asset's own configuration is there to restart it by hand, with its own certificate
    for aid in online:
        cfg = (floor / "assets" / f"{aid}.toml").read_text()
        assert f'id = "{aid}"' in cfg and "insecure = false" in cfg
        assert (floor / "assets" / aid / "certs" / "client-operator.der").is_file()
    info = json.loads((floor / "cps.json").read_text())
    assert info["mode"] == "processes"


def test_a_unit_killed_with_minus_9_goes_offline_and_rejoins_when_restarted(floor):
    pid = asset(status(floor), "TU_A")["pid"]
    os.kill(pid, signal.SIGKILL)
    _, took = wait_for(floor, lambda d: not asset(d, "TU_A")["online"], 10.0, "TU_A offline")
    assert took < 10.0
    proc = start(floor, "TU_A")
    doc, _ = wait_for(floor, lambda d: asset(d, "TU_A")["online"], 60.0, "TU_A back")
    assert asset(doc, "TU_A")["pid"] == proc.pid != pid
    # it resumed what it had persisted: o1 still lies on it
    state = json.loads((floor / "assets" / "TU_A" / "state" / "TU_A.json").read_text())
    assert state["possessed"] == ["o1"]


def test_a_module_joins_at_runtime_and_a_leave_is_announced(floor):
    proc = start(floor, "TM_2")
    deadline = time.monotonic() + 90
    log = floor / "logs" / "TM_2.log"
    while "TM_2 up at" not in (log.read_text() if log.exists() else ""):
        assert proc.poll() is None and time.monotonic() < deadline, log.read_text()
        time.sleep(0.2)
    _, took = wait_for(floor, lambda d: asset(d, "TM_2")["online"], 5.0, "TM_2 joined")
    assert took <= 5.0
    proc.send_signal(signal.SIGTERM)  # a clean leave: announced, exit 0
    assert proc.wait(30) == 0
    wait_for(floor, lambda d: not asset(d, "TM_2")["online"], 3.0, "TM_2 left")
    start(floor, "TM_2")
    wait_for(floor, lambda d: asset(d, "TM_2")["online"], 90.0, "TM_2 back")


def test_orders_flow_and_a_module_killed_mid_operation_loses_nothing(floor):
    first = tt("cps", "order", "--workdir", str(floor), "--to", "TU_B", "--object", "o1",
               timeout=300)  # fmt: skip
    assert first.returncode in (0, 3), first.stderr
    op1 = first.stdout.split()[1].rstrip(":")
    doc = status(floor)
    objects_consistent(doc)
    # a second order; kill the module that took it while it works
    obj = "o2" if not doc["objects"]["o2"]["unknown"] else "o1"
    target = "TU_A" if doc["objects"][obj]["location"] != "TU_A" else "TU_B"
    proc = subprocess.Popen([sys.executable, "-m", "transfertwin", "cps", "order", "--workdir",
                             str(floor), "--to", target, "--object", obj],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)  # fmt: skip

    busy = module_at_work(floor, obj)
    os.kill(busy["pid"], signal.SIGKILL)
    out, err = proc.communicate(timeout=120)
    assert proc.returncode == 3, out + err  # failed, with the module and the step named
    op2 = out.split()[1].rstrip(":")
    assert op2 != op1  # ids are unique on the floor
    assert "finished: failed" in out and f"{busy['id']} went offline" in out, out
    doc = status(floor)
    objects_consistent(doc)
    assert doc["objects"][obj].get("moving") is None
    if doc["objects"][obj]["unknown"]:  # lost mid-transfer: where it was last seen, by op2
        assert doc["objects"][obj]["operation"] == op2
    # the module comes back with its state; the floor takes orders again
    start(floor, busy["id"])
    wait_for(floor, lambda d: asset(d, busy["id"])["online"], 90.0, "module back")


def test_trust_is_per_asset_process(floor, tmp_path):
    """A client certificate no asset trusts is refused; trusted for one asset, only that
    asset accepts it (`cps trust --asset`)."""
    import asyncio

    from asyncua import ua

    from transfertwin.cps.opcua import connect, ensure_certificate, load_credentials

    info = json.loads((floor / "cps.json").read_text())
    creds = load_credentials(Path(info["credentials_file"]))
    endpoint = {a["id"]: a["endpoint"] for a in info["assets"]}
    mine = tmp_path / "client"

    async def read(aid: str) -> object:
        async with connect(endpoint[aid], aid, credentials=creds, cert_dir=mine,
                           timeout_s=10) as s:  # fmt: skip
            return await s.read("OperationalData", "PossessedObjects")

    def refused(aid: str) -> bool:
        try:
            asyncio.run(read(aid))
        except ua.UaStatusCodeError as exc:
            return exc.code == ua.StatusCodes.BadCertificateUntrusted
        return False

    cert, _ = asyncio.run(ensure_certificate(mine, "client-operator"))
    assert refused("TU_B")
    out = tt("cps", "trust", str(cert), "--workdir", str(floor), "--asset", "TU_B")
    assert out.returncode == 0, out.stderr
    assert asyncio.run(read("TU_B")) is not None
    assert refused("TU_A")
