"""`transfertwin cps up/status/order` as a user runs them, against the test run's one
`cps up --plant-seed` (conftest.py: `plant_cps`; the plant's units are assets beside the 14
of the demo), and a clean SIGTERM shutdown of it (the last test to use it). `cps up`, the two
concurrent orders and `-v` run in processes of their own; the other commands through
`transfertwin.cli.main` in the test's process (`run_main`).

Item by item (issue 15): refusals reach the client at once with the reason; the TMS knows
where every object is and refuses impossible or concurrent orders; stderr stays quiet
without -v; the status table shows whole endpoints at 80 columns.
"""

from __future__ import annotations

import asyncio
import json
import time
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import pytest

from tests.integration.cps._cli import RunningCps, run_main
from tests.integration.cps._cli import tt as _tt


@pytest.fixture
def cps(plant_cps: RunningCps) -> RunningCps:
    return plant_cps


def test_cps_is_up_and_quiet_without_verbose(cps):
    from transfertwin.cps import demo_descriptors, plant_descriptors

    assert cps.first_line.startswith("CPS up: 18 assets"), cps.first_line
    info = json.loads((cps.wd / "cps.json").read_text())
    assert len(info["assets"]) == 18
    demo = {d.asset_id for d in demo_descriptors()}
    assert len(demo) == 14  # the demo's 14 assets, and the plant's 4 units
    assert {a["id"] for a in info["assets"]} == demo | {d.asset_id for d in plant_descriptors()}
    creds = json.loads((cps.wd / "credentials.json").read_text())
    assert set(creds) == {"operator", "viewer"}
    # The log goes to cps.log; stderr has no INFO lines and no asyncua certificate warnings.
    assert "TU_A joined" in (cps.wd / "cps.log").read_text()
    assert cps.stderr_path.read_text() == ""


@pytest.mark.parametrize(
    ("source", "target", "obj", "reason"),
    [
        ("TU_A", "TU_Z", "o5", "--to TU_Z: no such transfer unit"),
        ("TU_A", "TU_C", "o99", "--object o99: not an object of this floor"),
        ("TU_B", "TU_B", "o2", "--from and --to are both TU_B"),
        ("TU_B", "TU_C", "o4", "the TMS refused the order: o4 is at TU_D, not at TU_B"),
    ],
)
def test_impossible_orders_are_refused_at_once_with_the_reason(cps, capfd, source, target, obj,
                                                                reason):  # fmt: skip
    t0 = time.monotonic()
    res = run_main(capfd, *cps.order_args(source, target, obj))
    took = time.monotonic() - t0
    assert res.returncode == 2, res.stderr
    lines = res.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith(f"transfertwin: error: {reason}"), res.stderr
    assert "submitted" not in res.stdout
    assert took < 45  # no wait for a timeout (it was 60 s)


def test_the_tms_refuses_itself_what_a_client_does_not_check(cps):
    """A client that skips the checks (any OPC UA client) gets a Bad status and the reason."""
    from transfertwin.cps.opcua import OperationRefused, connect, load_credentials

    info = json.loads((cps.wd / "cps.json").read_text())
    tms_url = next(a["endpoint"] for a in info["assets"] if a["id"] == "TMS")

    async def call(*args):
        async with connect(tms_url, "TMS", credentials=load_credentials(
                cps.wd / "credentials.json"), cert_dir=cps.wd / "certs") as tms:  # fmt: skip
            with pytest.raises(OperationRefused) as refused:
                await tms.call("SubmitTransportOperation", *args)
            return refused.value

    for args, status, reason in [
        (("TU_A", "TU_Z", "o5"), "BadInvalidArgument",
         "no transfer unit or destination group 'TU_Z'"),
        (("TU_A", "TU_C", "o9"), "BadInvalidArgument", "'o9' is not an object of this floor"),
        (("TU_B", "TU_B", "o2"), "BadInvalidArgument", "o2 is at TU_B already"),
        (("TU_A", "TU_C", "o4"), "BadInvalidState", "o4 is at TU_D, not at TU_A"),
    ]:
        refused = asyncio.run(call(*args))
        assert refused.status == status and reason in refused.reason, refused


def test_order_moves_the_object_and_concurrent_orders_cannot_both_win(cps, capfd):
    # Two orders for o2 (on TU_B) at the same time: exactly one is accepted.
    with ThreadPoolExecutor(2) as pool:
        first, second = pool.map(lambda t: cps.order("TU_B", t, "o2"), ("TU_D", "TU_C"))
    # accepted: delivered (0) or failed on the floor (3, an outcome); refused: 2
    accepted = [r for r in (first, second) if r.returncode in (0, 3)]
    refused = [r for r in (first, second) if r.returncode not in (0, 3)]
    assert len(accepted) == 1 and len(refused) == 1, (first.stderr, second.stderr)
    assert refused[0].returncode == 2
    # refused while the other moves o2, or (if that one was already done) because o2 left
    assert ("o2 is being moved by op" in refused[0].stderr
            or "o2 is at " in refused[0].stderr), refused[0].stderr  # fmt: skip
    out = accepted[0].stdout
    target = "TU_D" if accepted[0] is first else "TU_C"
    assert "submitted op" in out and ": docking" in out  # the operation's steps, as they come
    last = out.strip().splitlines()[-1]
    where = {"delivered": target, "failed at pick-up": "TU_B", "failed at delivery": "TM_1"}
    status = next(s for s in where if f"finished: {s};" in last)
    assert f"o2 is at {where[status]}" in last, last

    # The location is state of the system: the knowledge graph (status) and the object's AAS.
    st = run_main(capfd, "cps", "status", "--workdir", str(cps.wd))
    assert st.returncode == 0 and st.stderr == "", st.stderr
    objects = st.stdout.split("objects (TMS ledger)")[1]
    row = next(line.split() for line in objects.splitlines() if line.startswith("o2 "))
    assert where[status] in row
    assert _read(cps.wd, "o2", "PossessedBy") == where[status]
    if where[status] != "TU_B":  # o2 has left TU_B: the old route is refused now
        again = run_main(capfd, *cps.order_args("TU_B", target, "o2"))
        assert again.returncode == 2
        refusal = ("TM_1 carries o2" if where[status] == "TM_1"  # the module holds it
                   else f"o2 is at {where[status]}, not at TU_B")
        assert refusal in again.stderr, again.stderr


def _read(wd: Path, asset: str, prop: str):
    from transfertwin.cps.opcua import connect, load_credentials

    info = json.loads((wd / "cps.json").read_text())
    url = next(a["endpoint"] for a in info["assets"] if a["id"] == asset)

    async def read():
        async with connect(url, asset, credentials=load_credentials(wd / "credentials.json"),
                           role="viewer", cert_dir=wd / "certs") as client:  # fmt: skip
            return await client.read("OperationalData", prop)

    return asyncio.run(read())


def test_status_shows_locations_and_whole_endpoints_at_80_columns(cps, capfd, monkeypatch):
    monkeypatch.setenv("COLUMNS", "80")
    res = run_main(capfd, "cps", "status", "--workdir", str(cps.wd))
    assert res.returncode == 0 and res.stderr == "", res.stderr
    info = json.loads((cps.wd / "cps.json").read_text())
    assets, objects = res.stdout.split("objects (TMS ledger)")
    for asset in info["assets"]:
        assert asset["endpoint"] in assets, asset["id"]
    header = assets.splitlines()[1].split()
    assert header == ["id", "class", "online", "state", "pid", "address", "why", "offline"]
    rows = {line.split()[0]: line for line in assets.splitlines()[2:]}
    assert set(rows) == {a["id"] for a in info["assets"]}
    located = {line.split()[0]: line.split()[1] for line in objects.splitlines()[2:]}
    assert located["o4"] == "TU_D"  # objects show where they lie
    assert rows["TU_A"].split()[1] == "transfer_unit"


def test_verbose_restores_info_on_stderr(cps):
    res = _tt("-v", "cps", "status", "--workdir", str(cps.wd))
    assert res.returncode == 0
    assert "INFO" in res.stderr


def test_sigterm_shuts_down_cleanly_and_status_then_says_not_running(plant_cps_to_stop, capfd):
    cps = plant_cps_to_stop
    code, out, took = cps.stop()
    assert code == 0 and "CPS down" in out and took < 60
    assert not (cps.wd / "cps.json").exists()
    res = run_main(capfd, "cps", "status", "--workdir", str(cps.wd))
    assert res.returncode == 2
    assert "not running" in res.stderr and len(res.stderr.strip().splitlines()) == 1


def test_cps_commands_need_a_running_cps(tmp_path, capfd):
    res = run_main(capfd, "cps", "status", "--workdir", str(tmp_path))
    assert res.returncode == 2
    assert "cps up" in res.stderr and len(res.stderr.strip().splitlines()) == 1


def test_cps_export_writes_valid_aas_in_every_format(tmp_path, capfd):
    from transfertwin.cps import read_export

    for suffix in (".json", ".xml", ".aasx"):
        out = tmp_path / f"demo{suffix}"
        res = run_main(capfd, "cps", "export", "--out", str(out), "--with-physical")
        assert res.returncode == 0, res.stderr
        assert "valid" in res.stdout
        ids = {obj.id for obj in read_export(out)}
        assert "https://transfertwin.dev/ids/aas/TU_A" in ids
        assert "https://transfertwin.dev/ids/aas/TU_A_P" in ids
    bad = run_main(capfd, "cps", "export", "--out", str(tmp_path / "demo.txt"))
    assert bad.returncode == 2 and not (tmp_path / "demo.txt").exists()
