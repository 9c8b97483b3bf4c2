"""A floor operated without its work folder (docs/how-to/asset-on-its-own-host.md): the
options that say where a floor is (``--workdir``, or ``--graph`` with ``--ca`` and
``--credential``), each misuse one line and exit code 2; and ``Lifecycle.Shutdown`` stopping
the nodes of a floor in one process, one asset at a time and then all."""

from __future__ import annotations

import asyncio
import json
import shutil

import pytest

from tests.integration.cps._cli import run_main, two_module_floor

GRAPH = "opc.tcp://127.0.0.1:9/transfertwin/KG"  # nothing answers there


@pytest.fixture(scope="module")
def credential(tmp_path_factory):
    """An operator credential folder and a certificate to pass as --ca (self-signed here:
    the refusals below come before any server is reached, or from none answering)."""
    from transfertwin.cps.opcua import ensure_certificate, new_credentials, write_credentials

    base = tmp_path_factory.mktemp("operator")
    cred = base / "cred"
    asyncio.run(ensure_certificate(cred, "client-operator"))
    write_credentials(cred / "credentials.json", new_credentials())
    shutil.copy(cred / "client-operator.der", base / "ca.der")
    return base


@pytest.mark.parametrize(("args", "message"), [
    ((), "give the floor's --workdir (this host), or --graph URL with --ca and --credential"),
    (("--workdir", "w", "--graph", GRAPH), "give the floor's --workdir"),
    (("--graph", GRAPH), "--graph needs --ca"),
    (("--graph", "http://kg:4840/KG", "--ca", "ca.der", "--credential", "cred"),
     "not the knowledge graph's endpoint"),
    (("--graph", "opc.tcp://kg:4840/transfertwin/TMS", "--ca", "ca.der", "--credential", "cred"),
     "not the knowledge graph's endpoint"),
    (("--graph", GRAPH, "--ca", "ca.der", "--credential", "."),
     "not an operator credential (no client-operator.der"),
    (("--graph", GRAPH, "--ca", "cred/credentials.json", "--credential", "cred"),
     "--ca cred/credentials.json: not a certificate"),
    (("--graph", GRAPH, "--ca", "ca.der", "--credential", "cred"),
     "the knowledge graph is not answering"),
    (("--workdir", "w", "--ca", "ca.der"), "--ca and --credential go with --graph"),
])  # fmt: skip
@pytest.mark.parametrize("command", [("status",), ("orders",), ("kpis",), ("down",),
                                     ("locate", "--object", "o1", "--at", "TU_A"),
                                     ("order", "--object", "o1", "--to", "TU_A")])  # fmt: skip
def test_where_the_floor_is_is_checked_in_one_line(credential, capfd, monkeypatch, command,
                                                   args, message):  # fmt: skip
    monkeypatch.chdir(credential)
    done = run_main(capfd, "cps", *command, *args)
    assert done.returncode == 2, (done.stdout, done.stderr)
    lines = done.stderr.strip().splitlines()
    assert len(lines) == 1 and message in lines[0], done.stderr


@pytest.mark.parametrize("mode", [(), ("--single-process",)])
def test_a_floor_bound_to_other_hosts_is_not_started_here(tmp_path, capfd, mode):
    floor = tmp_path / "floor.toml"
    floor.write_text(two_module_floor("away", {"o1": "TU_A"}) + '\n[bind]\nTU_A = "198.18.0.250"\n')
    done = run_main(capfd, "cps", "up", "--floor", str(floor), "--workdir", str(tmp_path / "w"),
                    *mode)  # fmt: skip
    assert done.returncode == 2, done.stdout + done.stderr
    assert "TU_A is bound to 198.18.0.250, an address of another host" in done.stderr
    assert "--prepare-only" in done.stderr and not (tmp_path / "w" / "assets").exists()
    prepared = run_main(capfd, "cps", "up", "--floor", str(floor), "--workdir",
                        str(tmp_path / "w"), "--prepare-only")  # fmt: skip
    assert prepared.returncode == 0, prepared.stderr
    assert (tmp_path / "w" / "assets" / "TU_A" / "asset.toml").is_file()


@pytest.mark.parametrize(("args", "message"), [
    (("--cps", "w", "--graph", GRAPH), "choose one"),
    (("--graph", GRAPH), "--graph needs --ca"),
    (("--graph", GRAPH, "--ca", "ca.der", "--credential", "cred"),
     "the knowledge graph is not answering"),
])  # fmt: skip
def test_the_console_of_a_floor_elsewhere_is_checked_in_one_line(credential, capfd, monkeypatch,
                                                                args, message):  # fmt: skip
    monkeypatch.chdir(credential)
    done = run_main(capfd, "web", *args)
    assert done.returncode == 2 and message in done.stderr, (done.stdout, done.stderr)


def test_an_asset_needs_its_bundle_or_file(capfd):
    done = run_main(capfd, "cps", "asset")
    assert done.returncode == 2 and "give the asset's bundle folder" in done.stderr


@pytest.mark.parametrize("insecure", [True, False], ids=["insecure", "secure"])
def test_shutdown_stops_a_node_of_a_floor_in_one_process_and_the_last_ends_it(
        tmp_path, capfd, insecure):  # fmt: skip
    """Each asset's ``Lifecycle.Shutdown`` (what `cps down` calls, operator role): the node
    answers, leaves (the graph says so) and stops; the floor ends with its last node. `cps
    down --asset` stops one asset so, and never signals the process the others share. On a
    secure floor too, where the assets' own certificates may not call it (the operator's
    credential does)."""
    from transfertwin.cps import LocalFloor, load_floor
    from transfertwin.cps.node import LIFECYCLE

    (tmp_path / "floor.toml").write_text(two_module_floor("shutdown", {"o1": "TU_A"}))
    floor = load_floor(tmp_path / "floor.toml")

    async def main() -> None:
        async with LocalFloor(floor, tmp_path / "w", insecure=insecure, lease_s=2.0) as local:
            down = await asyncio.to_thread(run_main, capfd, "cps", "down", "--workdir",
                                           str(tmp_path / "w"), "--asset", "o1")  # fmt: skip
            assert down.returncode == 0, down.stderr
            assert "stopped 1 assets (1 over OPC UA, 0 by signal)" in down.stdout, down.stdout
            assert "o1" not in local.nodes and "TU_A" in local.nodes  # the process goes on
            async with local.client("KG") as kg:
                rows = {a["id"]: a for a in json.loads(await kg.call("Status"))["assets"]}
            assert not rows["o1"]["online"] and rows["o1"]["offline"]["reason"] == "left"
            assert not local.ended.is_set()  # the others go on
            for aid in [a for a in local.nodes if a != "KG"] + ["KG"]:
                async with local.client(aid) as c:
                    await c.call("Shutdown", submodel=LIFECYCLE)
            await asyncio.wait_for(local.ended.wait(), 30)
            assert local.nodes == {}

    asyncio.run(asyncio.wait_for(main(), 120))
