"""The console's replay routes over HTTP (Starlette TestClient): the page and its vendored
three.js, a study row's replay with the stored row's bits, a transfer's replay, and errors as
JSON with a 4xx status."""

from __future__ import annotations

import pytest
from starlette.testclient import TestClient

from transfertwin.store import SQLiteResultStore
from transfertwin.web import WebConfig, create_app
from transfertwin.web._replay import replay_query

LOOPBACK = "http://127.0.0.1"


@pytest.fixture(scope="module")
def calibration(tmp_path_factory):
    """`calibrate run` on the first 3 real rows, 2 runs (6 experiments)."""
    from transfertwin.cli import main

    out = tmp_path_factory.mktemp("cal") / "cal3"
    assert main(["calibrate", "run", "--limit", "3", "--runs", "2", "--workers", "1",
                 "--out", str(out)]) == 0  # fmt: skip
    return out


@pytest.fixture(scope="module")
def client(tiny_study, calibration):
    cfg = WebConfig(dbs=(tiny_study,), calibrations=(calibration,))
    with TestClient(create_app(cfg), base_url=LOOPBACK, raise_server_exceptions=False) as c:
        yield c


def test_the_page_and_three_js_are_served_locally(client):
    page = client.get("/replay?object=o1")
    assert page.status_code == 200
    for src in ("/static/replay.js", "/static/replay-fetch.js", "/static/replay.css",
                "/static/vendor/three/three.module.js"):  # fmt: skip
        assert src in page.text
        assert client.get(src).status_code == 200
    for src in ("three.core.js", "OrbitControls.js", "LICENSE", "README.md"):
        assert client.get(f"/static/vendor/three/{src}").status_code == 200
    assert "https://" not in client.get("/static/replay.js").text  # no CDN


def test_a_study_row_replays_with_the_stored_bits(client, tiny_study):
    with SQLiteResultStore(tiny_study, create=False) as store:
        row = next(r for r in store.rows() if r["status"] == "ok")
    res = client.get("/api/replay?" + replay_query(tiny_study.name, row))
    assert res.status_code == 200, res.text
    doc = res.json()
    assert doc["source"] == {"kind": "study", "study": tiny_study.name, "stored": True,
                             "check": {"same": True, "differences": []}, "runs": 1}  # fmt: skip
    assert doc["result"]["t_end_s"] == row["t_end_s"] and doc["spec"]["seed"] == row["seed"]
    assert doc["markers"][1]["kind"] == "pre"


def test_a_transfer_replay_and_bad_requests(client):
    q = "object=o1&face=front&conveyor=both&theta=90&seed=3&gap_mm=80"
    doc = client.get(f"/api/replay?{q}").json()
    assert doc["markers"][-1]["kind"] == "failure" and doc["source"] == {"kind": "transfer"}
    bad = {
        "object=/etc/passwd&face=front&conveyor=both&theta=0": (422, "built-in"),
        "object=o1&face=front&conveyor=both&theta=abc": (422, "theta must be an integer"),
        "object=o1&conveyor=both&theta=0": (422, "face"),
        "object=o1&face=front&conveyor=both&theta=0&dock_error=1,2": (422, "--dock-error"),
        "study=nope.sqlite&object=o1&face=front&conveyor=both&theta=0&run=0": (404, "no study"),
        "key=nothing": (404, "no replay"),
    }
    for query, (status, words) in bad.items():
        res = client.get(f"/api/replay?{query}")
        assert res.status_code == status, (query, res.text)
        assert words in res.json()["error"]


def test_calibration_rows_link_to_replays_that_agree_with_the_predictions(client):
    view = client.get("/api/calibrations/cal3").json()
    assert view["rows_total"] == 3 and [r["row"] for r in view["rows"]] == [0, 1, 2]
    for row in view["rows"]:
        for run, predicted in enumerate(row["predicted"]):
            res = client.get(f"/api/replay?calibration=cal3&row={row['row']}&run={run}")
            assert res.status_code == 200, res.text
            src = res.json()["source"]
            assert (src["predicted"], src["real_success"]) == (predicted, row["success"])
            assert src["agrees"] is True, src  # the same experiment as calibrate ran
    for query, status in (("calibration=cal3&row=3&run=0", 422),
                          ("calibration=cal3&row=0&run=2", 422),
                          ("calibration=other&row=0&run=0", 404)):  # fmt: skip
        assert client.get(f"/api/replay?{query}").status_code == status
