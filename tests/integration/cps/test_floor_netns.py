"""A floor across hosts, each host a network namespace (docs/how-to/asset-on-its-own-host.md).

`cps up --prepare-only` writes one bundle per asset; each bundle is copied into a folder of
its own (a host's disk: nothing shared, nothing hard-linked) and started there with `cps
asset BUNDLE`, inside a namespace of its own whose only interface is on a bridge, at a
198.18.0.x address the floor file binds it to, its loopback down. The operator, in another
namespace, holds only the graph's endpoint, the CA certificate and an operator credential.
Checked: every asset online at its address; an order delivered; the web console on the
operator's host (``web --graph``) showing every asset live; no file shared between the
hosts' folders; a rogue server posing as the graph captures no credential; a standby module
joins with a certificate newly signed for it; a killed asset rejoins; a revoked asset goes
offline; `cps down --graph` stops the floor over OPC UA; every namespace and interface the
test made is gone at the end, also when it fails.
"""

from __future__ import annotations

import contextlib
import json
import os
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from tests.integration.cps._netns import NamespaceNet, netns_unavailable

#: Seven asset hosts, the operator and a rogue (~2-3 min on 2 cores): slow, run by .ci/run.
pytestmark = pytest.mark.slow

ADDRESS = {"KG": "198.18.0.10", "TMS": "198.18.0.11", "TU_A": "198.18.0.12",
           "TU_B": "198.18.0.13", "TM_1": "198.18.0.14", "o2": "198.18.0.15",
           "TM_2": "198.18.0.16"}  # fmt: skip
OPERATOR, ROGUE = "198.18.0.20", "198.18.0.66"
GRAPH = f"opc.tcp://{ADDRESS['KG']}:4840/transfertwin/KG"
LEASE_S = 3.0

FLOOR = f"""
name = "hosts"
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

[[module]]
id = "TM_1"
x_m = 6.0
y_m = 5.2

[[module]]
id = "TM_2"
x_m = 6.0
y_m = 3.0
standby = true

[[object]]
id = "o2"
at = "TU_A"

[operation]
policy = "nearest-idle"

[bind]
{chr(10).join(f'{aid} = "{addr}"' for aid, addr in ADDRESS.items())}
"""

#: A server that poses as the floor's graph (its own self-signed certificate naming
#: urn:transfertwin:KG) and writes down every user name and password it is sent.
ROGUE_SERVER = r"""
import asyncio, json, sys
from pathlib import Path
from asyncua import Server, ua
from asyncua.crypto.cert_gen import setup_self_signed_certificate
from cryptography.x509.oid import ExtendedKeyUsageOID

host, folder = sys.argv[1], Path(sys.argv[2])
captured = folder / "captured.jsonl"

class Capture:
    def get_user(self, iserver, username=None, password=None, certificate=None):
        with captured.open("a") as f:
            f.write(json.dumps({"user": username, "password": password}) + "\n")
        return None

async def main():
    key, cert = folder / "rogue.pem", folder / "rogue.der"
    await setup_self_signed_certificate(key, cert, "urn:transfertwin:KG", host,
        [ExtendedKeyUsageOID.CLIENT_AUTH, ExtendedKeyUsageOID.SERVER_AUTH],
        {"commonName": "KG"})
    server = Server(user_manager=Capture())
    await server.init()
    server.set_endpoint(f"opc.tcp://{host}:4840/transfertwin/KG")
    server.set_server_name("KG")
    await server.set_application_uri("urn:transfertwin:KG")
    server.set_security_policy([ua.SecurityPolicyType.Basic256Sha256_SignAndEncrypt])
    await server.load_certificate(str(cert))
    await server.load_private_key(str(key))
    async with server:
        print("rogue up", flush=True)
        await asyncio.sleep(3600)

asyncio.run(main())
"""


@pytest.fixture
def net():
    why = netns_unavailable()
    if why is not None:
        pytest.skip(f"this machine cannot make network namespaces: {why}")
    made = NamespaceNet(f"tt{os.getpid() % 100000}")
    procs: list[subprocess.Popen] = []
    made.procs = procs
    try:
        yield made
    finally:
        for p in procs:
            if p.poll() is None:
                p.kill()
        for p in procs:
            with contextlib.suppress(subprocess.TimeoutExpired):
                p.wait(10)
        made.remove()
        assert made.left() == [], made.left()  # nothing the test made is left


def _tt(net: NamespaceNet, host: str, cwd: Path, *args: str, timeout: float = 60):
    """`transfertwin ARGS` on `host`, in folder `cwd`."""
    return subprocess.run(net.command(host, [sys.executable, "-m", "transfertwin", *args]),
                          cwd=cwd, capture_output=True, text=True, timeout=timeout)  # fmt: skip


def _start(net: NamespaceNet, aid: str, home: Path, logs: Path) -> subprocess.Popen:
    """Asset `aid` from the bundle in its host's folder `home`, on its host."""
    with (logs / f"{aid}.log").open("ab") as out:
        proc = subprocess.Popen(
            net.command(aid, [sys.executable, "-m", "transfertwin", "cps", "asset", str(home)]),
            stdout=out, stderr=subprocess.STDOUT, stdin=subprocess.DEVNULL,
            env={**os.environ, "PYTHONUNBUFFERED": "1"}, start_new_session=True)  # fmt: skip
    net.procs.append(proc)
    return proc


def _files(folder: Path) -> dict[Path, os.stat_result]:
    return {p: p.stat() for p in folder.rglob("*") if p.is_file()}


def test_a_floor_across_hosts_runs_from_bundles_and_is_operated_from_elsewhere(net, tmp_path):
    from transfertwin.cps.opcua import install_certificate, load_ca, new_request

    (tmp_path / "floor.toml").write_text(FLOOR)
    wd, hosts, logs = tmp_path / "w", tmp_path / "hosts", tmp_path / "logs"
    logs.mkdir()
    up = subprocess.run([sys.executable, "-m", "transfertwin", "cps", "up", "--floor",
                         str(tmp_path / "floor.toml"), "--workdir", str(wd), "--prepare-only",
                         "--time-scale", "0", "--lease", str(LEASE_S)],
                        capture_output=True, text=True, timeout=120)  # fmt: skip
    assert up.returncode == 0, up.stderr
    # each host's disk: a copy of its bundle only; the operator's: endpoint, CA, credential
    for aid in ADDRESS:
        shutil.copytree(wd / "assets" / aid, hosts / aid)
    op = tmp_path / "operator"
    (op / "cred").mkdir(parents=True)
    for name in ("client-operator.der", "client-operator.pem"):
        shutil.copy(wd / "certs" / name, op / "cred" / name)
    shutil.copy(wd / "credentials.json", op / "cred" / "credentials.json")
    shutil.copy(wd / "ca" / "ca.der", op / "ca.der")
    remote = ("--graph", GRAPH, "--ca", "ca.der", "--credential", "cred")
    for aid, address in ADDRESS.items():
        assert net.add(aid, address) == address and not net.loopback_up(aid)
    net.add("operator", OPERATOR)
    procs = {aid: _start(net, aid, hosts / aid, logs) for aid in ("KG", "TMS")}
    time.sleep(2.0)  # the seeds listen first (as cps up starts them), then the rest
    procs |= {aid: _start(net, aid, hosts / aid, logs) for aid in ADDRESS
              if aid not in ("KG", "TMS", "TM_2")}  # fmt: skip

    def status() -> dict:
        done = _tt(net, "operator", op, "cps", "status", *remote, "--json")
        return json.loads(done.stdout) if done.returncode == 0 else {"error": done.stderr}

    def until(check, what: str, timeout_s: float = 90.0) -> dict:
        deadline = time.monotonic() + timeout_s
        while True:
            doc = status()
            if "error" not in doc and check({a["id"]: a for a in doc["assets"]}):
                return doc
            dead = {a: p.returncode for a, p in procs.items() if p.poll() is not None}
            assert time.monotonic() < deadline and not dead, (
                what, doc, dead, {a: (logs / f"{a}.log").read_text()[-600:] for a in dead})
            time.sleep(2.0)

    running = [a for a in ADDRESS if a != "TM_2"]
    doc = until(lambda rows: all(rows.get(a, {}).get("online") for a in running),
                "every asset online", 150)  # fmt: skip
    for a in doc["assets"]:  # each at the address its host has, on the floor's port
        if a["id"] in running:
            assert a["address"] == f"opc.tcp://{ADDRESS[a['id']]}:4840/transfertwin/{a['id']}"
    assert doc["objects"]["o2"]["location"] == "TU_A"

    # an order, from the operator's host, delivered
    order = _tt(net, "operator", op, "cps", "order", *remote, "--object", "o2", "--to",
                "TU_B", "--timeout", "150", timeout=200)  # fmt: skip
    assert order.returncode == 0, order.stdout + order.stderr
    assert "o2 is at TU_B" in order.stdout.splitlines()[-1]
    kpis = _tt(net, "operator", op, "cps", "kpis", *remote, "--json")
    assert json.loads(kpis.stdout)["delivered"] == 1, kpis.stderr
    orders = _tt(net, "operator", op, "cps", "orders", *remote, "--json")
    assert [o["state"] for o in json.loads(orders.stdout)] == ["done"], orders.stderr
    located = _tt(net, "operator", op, "cps", "locate", *remote, "--object", "o2", "--at", "TU_B")
    assert located.returncode == 0 and "o2 is at TU_B" in located.stdout, located.stderr
    assert sorted(p.name for p in op.rglob("*")) == ["ca.der", "client-operator.der",
                                                     "client-operator.pem", "cred",
                                                     "credentials.json"]  # nothing else there

    # the web console on the operator's host, from the same three things
    net.bring_loopback_up("operator")  # the console listens on its own host's loopback
    console = subprocess.Popen(
        net.command("operator", [sys.executable, "-m", "transfertwin", "web", *remote,
                                 "--port", "18765"]),
        cwd=op, stdout=subprocess.PIPE, stderr=(logs / "console.log").open("ab"),
        text=True)  # fmt: skip
    net.procs.append(console)
    assert console.stdout.readline().startswith("console: http://127.0.0.1:18765")
    fetch = ("import json, urllib.request; print(json.dumps(json.load(urllib.request.urlopen("
             "'http://127.0.0.1:18765/api/assets', timeout=10))))")  # fmt: skip
    deadline = time.monotonic() + 60
    while True:
        got = subprocess.run(net.command("operator", [sys.executable, "-c", fetch]),
                             capture_output=True, text=True, timeout=30)  # fmt: skip
        seen = json.loads(got.stdout)["assets"] if got.returncode == 0 else []
        live = {a["id"] for a in seen if a["reachable"] and a["status"] == "online"}
        if set(running) <= live:
            break
        assert time.monotonic() < deadline, (got.stderr, seen, (logs / "console.log").read_text())
        time.sleep(2.0)
    console.send_signal(signal.SIGINT)
    console.wait(30)

    # no file shared or hard-linked between the hosts' folders
    seen: dict[tuple[int, int], Path] = {}
    for aid in ADDRESS:
        for path, st in _files(hosts / aid).items():
            assert st.st_nlink == 1, path
            assert (st.st_dev, st.st_ino) not in seen, (path, seen.get((st.st_dev, st.st_ino)))
            seen[(st.st_dev, st.st_ino)] = path
            assert not path.is_symlink(), path

    # a rogue server posing as the graph: the operator refuses it before any credential
    net.add("rogue", ROGUE)
    (tmp_path / "rogue").mkdir()
    with (logs / "rogue.log").open("ab") as out:
        rogue = subprocess.Popen(net.command("rogue", [sys.executable, "-c", ROGUE_SERVER, ROGUE,
                                                       str(tmp_path / "rogue")]),
                                 stdout=out, stderr=subprocess.STDOUT)  # fmt: skip
    net.procs.append(rogue)
    deadline = time.monotonic() + 60
    while "rogue up" not in (logs / "rogue.log").read_text():
        assert time.monotonic() < deadline and rogue.poll() is None, (
            (logs / "rogue.log").read_text())
        time.sleep(0.2)
    fooled = _tt(net, "operator", op, "cps", "status", "--graph",
                 f"opc.tcp://{ROGUE}:4840/transfertwin/KG", "--ca", "ca.der", "--credential",
                 "cred")  # fmt: skip
    assert fooled.returncode == 2, fooled.stdout + fooled.stderr
    captured = tmp_path / "rogue" / "captured.jsonl"
    assert not captured.exists() or captured.read_text() == "", captured.read_text()
    rogue.kill()

    # the standby module joins on its host with a certificate newly signed for it
    ca = load_ca(wd / "ca")
    certs = hosts / "TM_2" / "certs"
    for old in certs.iterdir():
        old.unlink()
    install_certificate(certs, "TM_2", ca.issue(new_request(certs, "TM_2", ADDRESS["TM_2"])))
    procs["TM_2"] = _start(net, "TM_2", hosts / "TM_2", logs)
    until(lambda rows: rows.get("TM_2", {}).get("online"), "TM_2 joined")

    # a killed asset rejoins: offline (its lease lapsed), started again from its bundle
    before = {a["id"]: a for a in status()["assets"]}["TU_A"]["instance"]
    killed = procs.pop("TU_A")
    os.kill(killed.pid, signal.SIGKILL)
    killed.wait(10)
    until(lambda rows: not rows["TU_A"]["online"], "TU_A offline", 30)
    procs["TU_A"] = _start(net, "TU_A", hosts / "TU_A", logs)
    rows = until(lambda rows: rows["TU_A"]["online"], "TU_A back")
    assert {a["id"]: a for a in rows["assets"]}["TU_A"]["instance"] != before

    # a revoked asset goes offline: the CA revokes o2, every host gets the new CRL
    ca.revoke("o2")
    for aid in ADDRESS:
        ca.install(hosts / aid / "trusted")
    t0 = time.monotonic()
    rows = until(lambda rows: not rows["o2"]["online"], "o2 offline", 6 * LEASE_S + 20)
    assert time.monotonic() - t0 < 6 * LEASE_S + 20
    time.sleep(2 * LEASE_S)  # and it stays off the floor
    assert not {a["id"]: a for a in status()["assets"]}["o2"]["online"]

    # shutdown over OPC UA from the operator's host: every asset on the floor stops
    down = _tt(net, "operator", op, "cps", "down", *remote, timeout=90)
    assert down.returncode == 0, down.stdout + down.stderr
    for aid, proc in procs.items():
        if aid != "o2":  # revoked: no one reaches it any more; the fixture ends it
            assert proc.wait(30) is not None, aid
    assert "left" in (logs / "TMS.log").read_text()
