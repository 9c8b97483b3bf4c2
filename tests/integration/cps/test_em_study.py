"""Studies through the Experiment Manager (issue 28, item 5). The EM's node in this process
(slow, ~25 s: three study processes spawned; CI runs this file's slow tests): StartStudy over
OPC UA runs a plan into a store with its progress in the EM's variables, StopStudy stops it,
the same plan resumes it, and a node that ends with a study running resumes it when it
comes back. On a process floor (slow): `cps study
start` runs a plan in the EM's process, `cps study status`, the console's Studies tab lists
the store; a study is stopped, resumed, and resumed again after the EM process is killed
with -9 and restarted by hand."""

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

FLOOR = """
name = "em-study"
size_m = [6.0, 4.0]
logical = ["KG", "TMS", "EM"]

[[station]]
name = "A"
x_m = 2.0
y_m = 2.0
yaw_deg = 90.0
mount = "left"

[[module]]
id = "TM_1"
x_m = 4.0
y_m = 2.0
standby = true
"""

#: 1 object, 2 states, 2 runs (the fixed docking error keeps the plan's check fast).
TINY = {"objects": ["o1"], "states": [["front", "left", 0], ["back", "both", 90]],
        "runs": 2, "seed": 3, "docking": {"fixed": [0.0, 0.0, 0.0]}}  # fmt: skip


def _em_config(tmp_path: Path):
    """The EM's configuration on a prepared (insecure, loopback) floor, with no seed peers:
    its node runs alone in this process."""
    import dataclasses

    from transfertwin.cps import load_floor, prepare_floor

    (tmp_path / "floor.toml").write_text(FLOOR)
    configs = prepare_floor(load_floor(tmp_path / "floor.toml"), tmp_path / "w", insecure=True)
    return dataclasses.replace(configs["EM"], seeds=())


@pytest.mark.slow
def test_the_em_node_runs_stops_and_resumes_a_study_over_opc_ua(tmp_path):
    from transfertwin.cps import asset_node
    from transfertwin.cps.opcua import OperationRefused, connect

    cfg = _em_config(tmp_path)
    plan = json.dumps(TINY | {"runs": 12})  # 24 experiments

    async def session(node, body):
        async with connect(node.server.endpoint, "EM", insecure=True, credentials=None,
                           timeout_s=30) as em:
            return await body(em)

    async def until(em, check, timeout_s: float = 60.0) -> dict:
        t0 = time.monotonic()
        while time.monotonic() - t0 < timeout_s:
            st = json.loads(await em.call("StudyStatus"))
            if check(st):
                return st
            await asyncio.sleep(0.1)
        raise AssertionError(f"not within {timeout_s} s: {st}")

    async def first(em) -> dict:
        with pytest.raises(OperationRefused, match="no study to resume"):
            await em.call("StartStudy", "", "")
        with pytest.raises(OperationRefused, match="unknown key"):
            await em.call("StartStudy", json.dumps(TINY | {"runz": 1}), "")
        st = json.loads(await em.call("StartStudy", plan, ""))
        assert st["planned"] == 24 and st["state"] in ("starting", "running")
        with pytest.raises(OperationRefused, match="a study is running"):
            await em.call("StartStudy", json.dumps(TINY), "")
        await until(em, lambda s: s["done"] >= 2)
        assert await em.read("OperationalData", "StudyState") == "running"
        assert await em.read("OperationalData", "StudyPlanned") == 24
        stopped = json.loads(await em.call("StopStudy"))
        assert stopped["state"] == "stopped" and 2 <= stopped["done"] < 24, stopped
        assert await em.read("OperationalData", "StudyDone") == stopped["done"]
        assert await em.read("OperationalData", "StudyEtaS") == -1.0
        resumed = json.loads(await em.call("StartStudy", plan, ""))  # the same plan resumes
        assert resumed["done"] == stopped["done"]
        return await until(em, lambda s: s["done"] >= stopped["done"] + 2)

    async def second(em) -> dict:
        return await until(em, lambda s: s["state"] == "finished")

    async def main() -> tuple[dict, dict]:
        async with asset_node(cfg) as node:
            running = await session(node, first)
        # the node ended with the study running (as on SIGTERM): it resumes on its own
        async with asset_node(cfg) as node:
            final = await session(node, second)
            assert await session(node, lambda em: em.read("OperationalData", "StudyProgress"))
        return running, final

    running, final = asyncio.run(main())
    assert running["state"] == "running"
    assert (final["done"], final["planned"]) == (24, 24)
    assert final["ran"] < 24 - running["done"] + 1  # what was stored before was not re-run
    from transfertwin.store import SQLiteResultStore

    with SQLiteResultStore(final["store"], create=False) as store:
        keys = [(r["face"], r["theta_deg"], r["run"]) for r in store.rows()]
    assert len(keys) == len(set(keys)) == 24


@pytest.fixture(scope="module")
def floor(tmp_path_factory):
    base = tmp_path_factory.mktemp("emfloor")
    (base / "floor.toml").write_text(FLOOR)
    wd = base / "w"
    up = tt("cps", "up", "--policy", "nearest-idle",
            "--floor", str(base / "floor.toml"), "--workdir", str(wd), "--detach",
            "--lease", "2", "--start-timeout", "150", timeout=200)  # fmt: skip
    assert up.returncode == 0, up.stderr
    started: list[subprocess.Popen] = []
    try:
        yield wd, started
    finally:
        tt("cps", "down", "--workdir", str(wd))
        for proc in started:
            if proc.poll() is None:
                proc.kill()


def _em_value(wd: Path, prop: str):
    from transfertwin.cli._cps_client import load_info
    from transfertwin.cps.opcua import connect

    info, creds = load_info(wd)
    endpoint = next(a["endpoint"] for a in info["assets"] if a["id"] == "EM")

    async def read():
        async with connect(endpoint, "EM", credentials=creds, role="operator",
                           cert_dir=Path(info["cert_dir"]), insecure=False) as em:  # fmt: skip
            return await em.read("OperationalData", prop)

    return asyncio.run(read())


def _status(wd: Path) -> dict:
    out = tt("cps", "study", "status", "--workdir", str(wd), "--json")
    assert out.returncode == 0, out.stderr
    return json.loads(out.stdout)


@pytest.mark.slow
def test_a_study_started_from_the_command_line_runs_in_the_em_and_shows_in_the_console(
    floor, tmp_path
):
    from starlette.testclient import TestClient

    from transfertwin.web import WebConfig, create_app

    wd, _ = floor
    plan = tmp_path / "plan.json"
    plan.write_text(json.dumps(TINY))
    assert _status(wd)["state"] == "none"
    run = tt("cps", "study", "start", "--workdir", str(wd), "--plan", str(plan), "--wait")
    assert run.returncode == 0, run.stderr
    assert "finished, 4/4 experiments (100%)" in run.stdout
    st = _status(wd)
    assert (st["state"], st["done"], st["planned"], st["eta_s"]) == ("finished", 4, 4, 0.0)
    store = Path(st["store"])
    assert store.is_relative_to(wd / "assets" / "EM" / "state") and store.is_file()
    # the EM's OPC UA variables
    assert _em_value(wd, "StudyState") == "finished"
    assert (_em_value(wd, "StudyDone"), _em_value(wd, "StudyPlanned")) == (4, 4)
    assert _em_value(wd, "StudyProgress") == 1.0
    assert _em_value(wd, "StudyStore") == str(store)
    # the same plan again: nothing left to run, the same store
    again = tt("cps", "study", "start", "--workdir", str(wd), "--plan", str(plan), "--wait")
    assert again.returncode == 0 and "finished, 4/4" in again.stdout, again.stderr
    # the console lists the EM's store and analyses it
    app = create_app(WebConfig(cps=wd))
    with TestClient(app, base_url="http://127.0.0.1:8765") as client:
        rows = client.get("/api/studies").json()["studies"]
        mine = next(s for s in rows if s["name"] == store.name)
        assert (mine["done"], mine["planned"], mine["objects"]) == (4, 4, ["o1"])
        analysis = client.get(f"/api/studies/{store.name}/analysis").json()
        assert analysis["object"] == "o1" and len(analysis["states"]) == 2


@pytest.mark.slow
def test_bad_plans_and_refusals_are_one_line_with_exit_code_2(floor, tmp_path):
    wd, _ = floor
    bad = tmp_path / "bad.json"
    bad.write_text(json.dumps(TINY | {"runz": 1}))
    out = tt("cps", "study", "start", "--workdir", str(wd), "--plan", str(bad))
    assert out.returncode == 2 and "unknown key(s) runz" in out.stderr
    assert len(out.stderr.strip().splitlines()) == 1
    bad.write_text("{not json")
    out = tt("cps", "study", "start", "--workdir", str(wd), "--plan", str(bad))
    assert out.returncode == 2 and "not JSON" in out.stderr
    # a store that holds another plan is refused before anything runs
    other = tmp_path / "other.json"
    other.write_text(json.dumps(TINY | {"seed": 4}))
    store = Path(_status(wd)["store"])
    out = tt("cps", "study", "start", "--workdir", str(wd), "--plan", str(other), "--store",
             str(store))  # fmt: skip
    assert out.returncode == 2 and "refused" in out.stderr, out.stderr


@pytest.mark.slow
def test_a_study_stops_resumes_and_survives_an_em_killed_with_minus_9(floor, tmp_path):
    wd, started = floor
    plan = tmp_path / "long.json"
    # 200 experiments: enough left after the resume that the EM is killed mid-study (with 60,
    # an unloaded host finished them between two polls)
    planned = 200
    plan.write_text(json.dumps(TINY | {"runs": planned // 2}))
    out = tt("cps", "study", "start", "--workdir", str(wd), "--plan", str(plan))
    assert out.returncode == 0, out.stderr

    def wait_done(n: int, timeout_s: float = 120.0, ended: bool = False) -> dict:
        """The status once `n` experiments are done (with `ended`: once the study ended;
        a restarted EM says 'starting' while it reads back what its store holds)."""
        t0 = time.monotonic()
        while time.monotonic() - t0 < timeout_s:
            try:
                st = _status(wd)
            except AssertionError:  # the EM restarting
                st = {"done": -1, "state": "?"}
            over = st["state"] in ("finished", "failed")
            if over or (not ended and (st["done"] or 0) >= n):
                return st
            time.sleep(0.5)
        raise AssertionError(f"{n} experiments not done within {timeout_s} s: {st}")

    wait_done(3)
    stop = tt("cps", "study", "stop", "--workdir", str(wd))
    assert stop.returncode == 0 and "stopped" in stop.stdout, stop.stdout + stop.stderr
    stopped = _status(wd)
    assert stopped["state"] == "stopped" and 3 <= stopped["done"] < planned
    time.sleep(2)
    assert _status(wd)["done"] == stopped["done"]  # nothing runs while stopped
    resume = tt("cps", "study", "resume", "--workdir", str(wd))
    assert resume.returncode == 0, resume.stderr
    before_kill = wait_done(stopped["done"] + 3)
    assert before_kill["state"] == "running", before_kill
    pid = int((wd / "assets" / "EM" / "state" / "pid").read_text())
    os.kill(pid, signal.SIGKILL)
    log = (wd / "logs" / "EM.restart.log").open("ab")
    started.append(subprocess.Popen(
        [sys.executable, "-m", "transfertwin", "cps", "asset", str(wd / "assets" / "EM")],
        stdout=log, stderr=subprocess.STDOUT, start_new_session=True))
    final = wait_done(planned, timeout_s=240.0, ended=True)
    assert (final["state"], final["done"], final["planned"]) == ("finished", planned,
                                                                 planned), final  # fmt: skip
    from transfertwin.store import SQLiteResultStore

    with SQLiteResultStore(final["store"], create=False) as store:
        keys = [(r["face"], r["theta_deg"], r["run"]) for r in store.rows()]
    assert len(keys) == len(set(keys)) == planned  # every experiment once
