"""The live transfer view over HTTP: a transfer started from the console runs a real E^V
(MuJoCo), its frames stream as server-sent events at >= 1 Hz and show the object crossing
the gap, and its outcome is the one `run_experiment` gives for the same spec (same seed,
same bits)."""

from __future__ import annotations

import json
import math
import time

from starlette.testclient import TestClient

from transfertwin.sim import DockingError, SceneConfig
from transfertwin.study.experiment import ExperimentSpec, run_experiment
from transfertwin.web import WebConfig, create_app

BODY = {"object": "o1", "face": "front", "conveyor": "both", "theta_deg": 90, "seed": 4,
        "speed": 4, "dock_error": [2, -1, 0.5]}  # fmt: skip


def _events(text: str) -> list[dict]:
    return [json.loads(line[6:]) for line in text.splitlines() if line.startswith("data: ")]


def test_a_started_transfer_streams_moving_frames_and_its_outcome():
    cfg = WebConfig()
    auth = {"Authorization": f"Bearer {cfg.session_token}"}
    with TestClient(create_app(cfg), base_url="http://127.0.0.1") as c:
        idle = _events(c.get("/api/transfer/live?max_events=2").text)
        assert [e["run"] for e in idle] == [None, None]  # a heartbeat while idle

        run = c.post("/api/transfer", json=BODY, headers=auth)
        assert run.status_code == 201, run.text
        assert c.post("/api/transfer", json=BODY, headers=auth).status_code == 409
        frames, seqs, t0, n_events = [], [], time.monotonic(), 0
        while True:
            for e in _events(c.get("/api/transfer/live?max_events=4").text):
                n_events += 1
                seqs.append(e["seq"])
                if e["frame"] is not None:
                    frames.append(e["frame"])
                geometry, last = e["geometry"], e["run"]
            if last["state"] != "running":
                break
            assert time.monotonic() - t0 < 120, "the transfer did not finish"
        elapsed = time.monotonic() - t0

    assert seqs == sorted(seqs)
    assert n_events >= elapsed  # >= 1 update per second
    xs = [f["centre"][0] for f in frames]
    assert min(xs) < -0.1 and max(xs) > 0.05  # from the TM across the gap onto the TU
    assert {"TM", "TU"} <= {f["possessed_by"] for f in frames}
    assert any(f["barriers"]["tu"]["near"] for f in frames)
    assert any(f["phase"] == "TM → TU" for f in frames)
    assert all(len(f["polygon"]) >= 3 for f in frames)
    assert {b["unit"] for b in geometry["belts"]} == {"tm", "tu"}

    spec = ExperimentSpec("o1", "front", "both", 90, seed=4, scene=SceneConfig(),
                          docking_error=DockingError(0.002, -0.001, math.radians(0.5)))  # fmt: skip
    direct = run_experiment(spec)
    outcome = last["outcome"]
    assert last["state"] == "finished"
    assert (outcome["status"], outcome["y1"], outcome["y2"], outcome["success"]) == (
        direct.status, direct.y1, direct.y2, direct.success)  # fmt: skip
    assert outcome["t_end_s"] == direct.t_end_s
