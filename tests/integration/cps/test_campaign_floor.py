"""A calibration campaign on a process floor with an emulated plant (issue 37, item 2;
slow, ~1 min): `cps campaign start` runs it in the Experiment Manager on the floor's
physical units; the EM is killed with -9 mid-campaign, restarted, and resumes it from its
journal (no E^P run twice); the finished campaign answers the TMS's `Predict` and shows in
each object's AAS; bad requests are one line with exit code 2."""

from __future__ import annotations

import asyncio
import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from tests.integration.cps._cli import tt

pytestmark = pytest.mark.slow

#: K E^P: enough that the EM is killed before they are done (about 7 a second here).
K = 60


@pytest.fixture(scope="module")
def floor(tmp_path_factory):
    wd = tmp_path_factory.mktemp("campaign") / "w"
    up = tt("cps", "up", "--workdir", str(wd), "--detach", "--time-scale", "0",
            "--plant-seed", "11", "--plant-kind", "mismatch", "--lease", "2",
            "--start-timeout", "200", timeout=260)  # fmt: skip
    assert up.returncode == 0, up.stderr
    started: list[subprocess.Popen] = []
    try:
        yield wd, started
    finally:
        tt("cps", "down", "--workdir", str(wd))
        for proc in started:
            if proc.poll() is None:
                proc.kill()


def _status(wd: Path) -> dict:
    out = tt("cps", "campaign", "status", "--workdir", str(wd), "--json")
    assert out.returncode == 0, out.stderr
    return json.loads(out.stdout)


def _call(wd: Path, asset: str, *, op: str | None = None, args=(), prop: str | None = None):
    from transfertwin.cli._cps_client import load_info
    from transfertwin.cps.opcua import connect

    info, creds = load_info(wd)
    endpoint = next(a["endpoint"] for a in info["assets"] if a["id"] == asset)

    async def go():
        async with connect(endpoint, asset, credentials=creds, role="operator",
                           cert_dir=Path(info["cert_dir"]), insecure=False) as s:  # fmt: skip
            return await (s.call(op, *args) if op else s.read("OperationalData", prop))

    return asyncio.run(go())


def test_bad_campaign_requests_are_one_line_with_exit_code_2(floor):
    wd, _ = floor
    for args, message in ((("--experiments", "2"), "'experiments' must be an integer"),
                          (("--objects", "o9"), "not objects of this floor")):  # fmt: skip
        out = tt("cps", "campaign", "start", "--workdir", str(wd), *args)
        assert out.returncode == 2 and message in out.stderr, out.stderr
        assert len(out.stderr.strip().splitlines()) == 1
    assert _status(wd)["state"] == "none"


def test_a_campaign_survives_an_em_killed_with_minus_9_and_publishes_predictions(floor):
    wd, started = floor
    out = tt("cps", "campaign", "start", "--workdir", str(wd), "--objects", "o1,o5",
             "--experiments", str(K), "--runs", "1", "--validation-runs", "2",
             "--theta-step", "90", "--seed", "2")  # fmt: skip
    assert out.returncode == 0, out.stderr
    campaign = out.stdout.split()[1].rstrip(":")

    def wait(check, timeout_s: float = 240.0) -> dict:
        t0, st = time.monotonic(), {}
        while time.monotonic() - t0 < timeout_s:
            try:
                st = _status(wd)
            except AssertionError:  # the EM restarting
                st = {}
            if st and check(st):
                return st
            time.sleep(0.3)
        raise AssertionError(f"not within {timeout_s} s: {st}")

    before = wait(lambda st: st["plant_experiments"] >= 5)
    assert before["state"] == "running" and before["plant_experiments"] < K, before
    pid = int((wd / "assets" / "EM" / "state" / "pid").read_text())
    os.kill(pid, signal.SIGKILL)
    log = (wd / "logs" / "EM.restart.log").open("ab")
    started.append(subprocess.Popen(
        [sys.executable, "-m", "transfertwin", "cps", "asset", str(wd / "assets" / "EM")],
        stdout=log, stderr=subprocess.STDOUT, start_new_session=True))  # fmt: skip
    final = wait(lambda st: st["state"] in ("finished", "failed"))
    assert final["state"] == "finished", final
    folder = Path(final["folder"])
    assert folder.is_relative_to(wd / "assets" / "EM" / "state" / "campaigns")
    entries = [json.loads(x) for x in (folder / "plant_journal.jsonl").read_text().splitlines()]
    keys = [e["key"] for e in entries]
    assert len(keys) == len(set(keys)) == final["plant_experiments"]  # none run twice
    assert sum(k.startswith("0:") for k in keys) == K
    assert final["floor_s"] > 0
    doc = json.loads((folder / "rehearsal.json").read_text())
    assert doc["training"] + doc["held_out"] == K

    # the TMS's predictions come from the campaign, both legs
    preds = json.loads(_call(wd, "EM", op="Predict", args=("o5", 4, 0)))
    assert preds and {p["source"] for p in preds} == {f"campaign {campaign}"}
    assert all(p["leg"] == "operation" and p["k_pickup"] is not None for p in preds)
    shown = json.loads(_call(wd, "o5", prop="PredictionsJson"))
    assert shown["campaign"] == campaign and shown["best"] == preds[0]
    assert shown["advice"].startswith("Put it ")  # decided as the study's report decides
    # the same request again: its outputs stand, nothing reruns
    again = tt("cps", "campaign", "start", "--workdir", str(wd), "--objects", "o1,o5",
               "--experiments", str(K), "--runs", "1", "--validation-runs", "2",
               "--theta-step", "90", "--seed", "2", "--wait")  # fmt: skip
    assert again.returncode == 0 and "finished" in again.stdout, again.stderr
    assert _status(wd)["plant_experiments"] == final["plant_experiments"]
    # the TMS plans o5's next order with the predictions in o5's AAS (an outcome either way)
    order = tt("cps", "order", "--workdir", str(wd), "--object", "o5", "--to", "TU_C")
    assert order.returncode in (0, 3), order.stderr
    ops = json.loads(_call(wd, "TMS", op="Orders"))
    status = _call(wd, "TMS", op="OperationStatus", args=(ops[-1]["operation"],))
    assert f"predictions of o5 from its AAS (campaign {campaign})" in status, status[:2000]
    # the KPIs count the campaign's floor time as a cost
    kpis = tt("cps", "kpis", "--workdir", str(wd), "--json")
    assert kpis.returncode == 0, kpis.stderr
    k = json.loads(kpis.stdout)
    assert k["calibration_floor_s"] == pytest.approx(final["floor_s"], abs=0.2)
    text = tt("cps", "kpis", "--workdir", str(wd)).stdout
    assert "calibration campaigns:" in text and "s of floor time" in text
