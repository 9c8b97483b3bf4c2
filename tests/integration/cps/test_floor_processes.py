"""The DT network with one process per asset (issue: the floor on a shop floor): a floor of
two transport modules as separate processes on their own loopback addresses, on the
emulated plant (`cps up --floor F --plant-seed N`: the module simulates its docked pair with
the plant's hidden physics). A unit killed with -9 is seen offline as a lapsed lease, one
stopped cleanly as a leave, both restarted by hand and seen again; a module killed in the
middle of an operation loses nothing; no file, status or log of the floor holds the plant's
seed or a hidden value. Slow (real time, ~90 s more): a module on standby joins at runtime
and leaves cleanly; orders flow on the plant's physics and a module is killed mid-operation
(run before the hidden-value check, which then reads the logs of those operations too)."""

from __future__ import annotations

import json
import os
import re
import signal
import stat
import subprocess
import sys
import time
from pathlib import Path

import pytest

from tests.integration.cps._cli import early_floor, run_main, tt, two_module_floor
from tests.integration.cps.test_plant_assets import _hidden_numbers, _patterns

FLOOR = two_module_floor("two-modules", {"o1": "TU_A"})  # TU_B free: orders need a free target

LEASE_S = 2.0

#: The floor's plant seed: a number that appears nowhere else in its files.
FLOOR_PLANT_SEED = 918273


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
        [sys.executable, "-m", "transfertwin", "cps", "asset", str(wd / "assets" / aid)],
        stdout=log, stderr=subprocess.STDOUT, start_new_session=True)  # its bundle
    STARTED.append(proc)
    return proc


#: The steps of an operation in which its module works.
WORKING = ("navigating", "docking", "scanning", "transferring")


def module_at_work(wd: Path, obj: str, timeout_s: float = 60.0, phases=WORKING) -> dict:
    """The module the TMS assigned the running operation for `obj`, once it is in one of
    `phases` (from the TMS's ledger: the graph's view of a module's state lags by a
    heartbeat)."""
    import asyncio

    from transfertwin.cli._cps_client import call_asset, load_info

    info, creds = load_info(wd)
    t0 = time.monotonic()
    while time.monotonic() - t0 < timeout_s:
        ledger = json.loads(asyncio.run(call_asset(info, creds, "TMS", "Ledger")))
        for op in ledger["operations"]:
            if (op["object"] == obj and op["state"] == "running"
                    and op["phase"] in phases):
                return asset(status(wd), op["module"])
        time.sleep(0.1)
    raise AssertionError(f"no operation for {obj} started within {timeout_s} s")


def unit_drive(wd: Path, unit: str) -> tuple[float, float, str]:
    """(left belt m/s, right belt m/s, docked module) as the unit's server shows them."""
    import asyncio

    from transfertwin.cli._cps_client import load_info
    from transfertwin.cps.opcua import connect

    info, creds = load_info(wd)
    url = next(a["endpoint"] for a in info["assets"] if a["id"] == unit)

    async def read():
        async with connect(url, unit, credentials=creds, role="viewer",
                           cert_dir=Path(info["cert_dir"])) as s:  # fmt: skip
            return tuple([await s.read("OperationalData", p) for p in
                          ("BeltSpeedLeft", "BeltSpeedRight", "DockedTransportModule")])

    return asyncio.run(read())


def objects_consistent(doc: dict) -> None:
    """Every object is in the ledger once, at an asset of the floor or unknown with where it
    was last seen."""
    assert set(doc["objects"]) == {"o1"}
    holders = {"TU_A", "TU_B", "TM_1", "TM_2"}
    for o, v in doc["objects"].items():
        if v["unknown"]:
            assert v["last_seen"] in holders and v["operation"].startswith("op"), (o, v)
        else:
            assert v["location"] in holders, (o, v)


#: The floor, started ahead by the folder's conftest (`early_floor`): in real time, so that a
#: kill lands in the middle of an operation.
EARLY_FLOOR = ("floor", FLOOR, ("--time-scale", "1", "--lease", str(LEASE_S), "--start-timeout",
                                "150", "--plant-seed", str(FLOOR_PLANT_SEED)))  # fmt: skip


@pytest.fixture(scope="module")
def floor(tmp_path_factory):
    early = early_floor(tmp_path_factory, *EARLY_FLOOR)
    up = early.result()
    assert up.returncode == 0, up.stderr
    # TU_A, TU_B, TM_1, o1, KG, TMS, and the plant's own TU_A_P and TU_B_P
    assert "8 asset processes" in up.stdout and "1 on standby" in up.stdout
    try:
        yield early.wd
    finally:
        down = early.stop()
        for proc in STARTED:
            if proc.poll() is None:
                proc.kill()
    assert down.returncode == 0 and "killed" not in down.stdout, down.stdout + down.stderr


def test_every_asset_is_its_own_process_on_its_own_address(floor):
    doc = status(floor)
    online = {a["id"]: a for a in doc["assets"] if a["online"]}
    assert set(online) == {"KG", "TMS", "TU_A", "TU_B", "TM_1", "o1", "TU_A_P", "TU_B_P"}
    assert len({a["pid"] for a in online.values()}) == 8
    hosts = {a["address"].split("//")[1].split(":")[0] for a in online.values()}
    assert len(hosts) == 8 and all(h.startswith("127.") for h in hosts)
    assert all(a["address"].startswith("opc.tcp://") for a in online.values())
    assert doc["objects"]["o1"] == {"location": "TU_A", "unknown": False, "moving": None}
    # each asset's own bundle is there to restart it by hand, with its own certificate
    for aid in online:
        cfg = (floor / "assets" / aid / "asset.toml").read_text()
        assert f'id = "{aid}"' in cfg and "insecure = false" in cfg
        assert (floor / "assets" / aid / "certs" / f"{aid}.der").is_file()  # the CA's
        trusted = floor / "assets" / aid / "trusted"
        assert sorted(p.name for p in trusted.iterdir()) == ["ca.der", "crl.der"]
    info = json.loads((floor / "cps.json").read_text())
    assert {a["id"]: a["config"] for a in info["assets"] if a["id"] in online} == {
        aid: str((floor / "assets" / aid / "asset.toml").resolve()) for aid in online}


def test_a_unit_killed_with_minus_9_lapses_one_stopped_leaves_and_both_rejoin(floor, capfd):
    doc = status(floor)
    killed, stopped = asset(doc, "TU_A")["pid"], asset(doc, "TU_B")["pid"]
    os.kill(killed, signal.SIGKILL)  # the host dies: no goodbye, the lease lapses
    os.kill(stopped, signal.SIGTERM)  # a clean stop: the leave is announced
    doc, took = wait_for(floor, lambda d: not asset(d, "TU_A")["online"]
                         and not asset(d, "TU_B")["online"], 10.0, "TU_A, TU_B offline")
    assert took < 10.0
    lapsed, left = asset(doc, "TU_A")["offline"], asset(doc, "TU_B")["offline"]
    assert lapsed["reason"] == "lapsed" and "lease expired" in lapsed["detail"], lapsed
    assert left["reason"] == "left" and left["detail"] == "announced its leave", left
    assert lapsed["since"] and 0 <= lapsed["since_s"] < 10
    assert asset(doc, "TM_1")["online"] and asset(doc, "TM_1")["offline"] is None
    # the standby module was prepared but never started: standby, not 'not answering'
    assert asset(doc, "TM_2")["state"] == "standby" and not asset(doc, "TM_2")["online"]
    shown = run_main(capfd, "cps", "status", "--workdir", str(floor))
    assert shown.returncode == 0, shown.stderr
    row = {line.split()[0]: line for line in shown.stdout.splitlines() if line.strip()}
    assert "OFFLINE" in row["TU_A"] and "lapsed" in row["TU_A"], shown.stdout
    assert "left" in row["TU_B"] and "standby" in row["TM_2"], shown.stdout
    procs = {aid: start(floor, aid) for aid in ("TU_A", "TU_B")}
    doc, _ = wait_for(floor, lambda d: asset(d, "TU_A")["online"] and asset(d, "TU_B")["online"],
                      60.0, "TU_A, TU_B back")  # fmt: skip
    assert asset(doc, "TU_A")["pid"] == procs["TU_A"].pid != killed
    assert asset(doc, "TU_A")["offline"] is None and asset(doc, "TU_A")["hal"] == "plant"
    # it resumed what it had persisted: o1 still lies on it
    state = json.loads((floor / "assets" / "TU_A" / "state" / "TU_A.json").read_text())
    assert state["possessed"] == ["o1"]


@pytest.mark.slow
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
    doc, _ = wait_for(floor, lambda d: not asset(d, "TM_2")["online"], 3.0, "TM_2 left")
    assert asset(doc, "TM_2")["offline"]["reason"] == "left"
    start(floor, "TM_2")
    wait_for(floor, lambda d: asset(d, "TM_2")["online"], 90.0, "TM_2 back")


@pytest.mark.slow
def test_orders_flow_and_a_module_killed_mid_operation_loses_nothing(floor):
    first = tt("cps", "order", "--workdir", str(floor), "--to", "TU_B", "--object", "o1",
               timeout=300)  # fmt: skip
    assert first.returncode in (0, 3), first.stderr
    op1 = first.stdout.split()[1].rstrip(":")
    doc = status(floor)
    objects_consistent(doc)
    # a second order; kill the module that took it while it works
    obj = "o1"
    if doc["objects"][obj]["unknown"]:  # lost in the gap: the operator puts it on TU_B
        put = tt("cps", "locate", "--workdir", str(floor), "--object", obj, "--at", "TU_B")
        assert put.returncode == 0, put.stderr
        doc = status(floor)
    target = "TU_A" if doc["objects"][obj]["location"] == "TU_B" else "TU_B"
    proc = subprocess.Popen([sys.executable, "-m", "transfertwin", "cps", "order", "--workdir",
                             str(floor), "--to", target, "--object", obj],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)  # fmt: skip

    busy = module_at_work(floor, obj, phases=("scanning", "transferring"))  # docked
    os.kill(busy["pid"], signal.SIGKILL)
    out, err = proc.communicate(timeout=120)
    assert proc.returncode == 3, out + err  # failed, with the module and the step named
    # no unit is left docked to the dead module with its belts running: each stopped its
    # belts and undocked it once the module's lease lapsed
    for unit in ("TU_A", "TU_B"):
        assert unit_drive(floor, unit) == (0.0, 0.0, ""), unit
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


def test_trust_is_per_asset_process(floor, tmp_path, capfd):
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
        # the client checks the servers against the floor's CA; the servers check it
        async with connect(endpoint[aid], aid, credentials=creds, cert_dir=mine,
                           trust_dir=Path(info["trust_dir"]), timeout_s=10) as s:  # fmt: skip
            return await s.read("OperationalData", "PossessedObjects")

    def refused(aid: str) -> bool:
        try:
            asyncio.run(read(aid))
        except ua.UaStatusCodeError as exc:
            return exc.code == ua.StatusCodes.BadCertificateUntrusted
        return False

    cert, _ = asyncio.run(ensure_certificate(mine, "client-operator"))
    assert refused("TU_B")
    out = run_main(capfd, "cps", "trust", str(cert), "--workdir", str(floor), "--asset", "TU_B")
    assert out.returncode == 0, out.stderr
    assert asyncio.run(read("TU_B")) is not None
    assert refused("TU_A")


def test_no_file_status_or_log_of_a_plant_floor_holds_a_hidden_value(floor):
    """The plant seed is in W/plant.secret only (owner-only); nothing else the floor wrote
    (asset files, cps.json, state, logs) nor its status holds the seed or a value drawn
    from it, after orders ran on the plant's physics."""
    hidden = _hidden_numbers(FLOOR_PLANT_SEED, ["o1"])
    pattern = _patterns(hidden)
    assert pattern.search(repr(hidden[0]))  # the search finds a hidden value written down
    seed_text = re.compile(rf"(?<![\d.]){FLOOR_PLANT_SEED}(?![\d.])")
    secret = floor / "plant.secret"
    assert secret.read_text().strip() == str(FLOOR_PLANT_SEED)
    assert stat.S_IMODE(secret.stat().st_mode) == 0o600
    for aid in ("TM_1", "TU_A"):  # their asset files name the seed file, not the seed
        cfg = (floor / "assets" / aid / "asset.toml").read_text()
        assert 'kind = "plant"' in cfg and 'plant_seed_file = "plant.secret"' in cfg, cfg
        own = floor / "assets" / aid / "plant.secret"  # a copy in the bundle, owner-only
        assert own.read_text() == secret.read_text()
        assert stat.S_IMODE(own.stat().st_mode) == 0o600
    assert not (floor / "assets" / "o1" / "plant.secret").exists()  # not on the plant
    texts = {"status": json.dumps(status(floor))}
    for path in floor.rglob("*"):
        if path.is_file() and path.name != secret.name and path.suffix in ("", ".toml",
                                                                           ".json", ".log"):
            texts[str(path.relative_to(floor))] = path.read_text(errors="replace")
    assert {"cps.json", "logs/TM_1.log", "assets/TM_1/asset.toml", "floor.toml"} <= set(texts)
    assert "TM_1 up at" in texts["logs/TM_1.log"]
    for where, text in texts.items():
        hit = pattern.search(text)
        assert hit is None, (where, hit and text[max(0, hit.start() - 80) : hit.end() + 80])
        assert not seed_text.search(text), where
