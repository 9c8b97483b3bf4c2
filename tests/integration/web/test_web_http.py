"""The console over HTTP (Starlette TestClient) against a real study store: pages, progress,
the success map, downloads, and the security rules (token, validation, no tracebacks)."""

from __future__ import annotations

import csv
import io
import json
import math
import subprocess
import sys

import pytest
from starlette.testclient import TestClient

from transfertwin.store import SQLiteResultStore
from transfertwin.web import MAX_BODY_BYTES, WebConfig, create_app

LOOPBACK = "http://127.0.0.1"


@pytest.fixture
def client(tiny_study):
    cfg = WebConfig(dbs=(tiny_study,))
    with TestClient(create_app(cfg), base_url=LOOPBACK, raise_server_exceptions=False) as c:
        c.app_state_token = cfg.session_token
        yield c


def _rows(db):
    with SQLiteResultStore(db, create=False) as store:
        return list(store.rows())


def test_page_and_assets_are_served_locally(client):
    page = client.get("/")
    assert page.status_code == 200
    for src in ("/static/app.js", "/static/style.css", "/static/vendor/plotly.min.js"):
        assert src in page.text
        assert client.get(src).status_code == 200
    assert "http://" not in page.text and "https://" not in page.text  # nothing from outside
    assert "plotly.js" in client.get("/static/vendor/plotly.min.js").text[:200]
    csp = page.headers["content-security-policy"]
    assert "default-src 'self'" in csp and "script-src 'self'" in csp


def test_progress_matches_the_store(client, tiny_study):
    rows = _rows(tiny_study)
    (s,) = client.get("/api/studies").json()["studies"]
    assert s["name"] == "tiny.sqlite"
    assert (s["done"], s["planned"]) == (len(rows), 12)
    assert s["by_status"] == {st: sum(r["status"] == st for r in rows) for st in s["by_status"]}
    assert s["rate_per_s"] > 0 and s["eta_s"] == pytest.approx(6 / s["rate_per_s"])
    assert s["objects"] == ["o1"]


def test_success_map_agrees_with_the_rows(client, tiny_study):
    m = client.get("/api/studies/tiny.sqlite/map").json()
    points = [p | {"face": f} for f, ps in m["objects"]["o1"].items() for p in ps]
    ok = [r for r in _rows(tiny_study) if r["status"] == "ok"]
    assert sum(p["n"] for p in points) == len(ok)
    for p in points:
        mine = [r for r in ok if (r["face"], r["conveyor"], r["theta_deg"]) ==
                (p["face"], p["conveyor"], p["theta_deg"])]  # fmt: skip
        assert p["share"] == pytest.approx(sum(r["success"] for r in mine) / len(mine))


def test_csv_and_parquet_downloads(client, tiny_study):
    res = client.get("/api/studies/tiny.sqlite/results.csv")
    assert res.status_code == 200 and "attachment" in res.headers["content-disposition"]
    table = list(csv.DictReader(io.StringIO(res.text)))
    rows = _rows(tiny_study)
    assert len(table) == len(rows)
    assert [int(t["success"]) for t in table] == [r["success"] for r in rows]
    assert all(not math.isnan(float(t["t_end_s"])) for t in table)
    pq = client.get("/api/studies/tiny.sqlite/results.parquet")
    assert pq.status_code == 200 and pq.content[:4] == b"PAR1"


@pytest.mark.parametrize(
    ("method", "path", "kwargs", "status"),
    [
        ("get", "/api/studies/nope.sqlite/map", {}, 404),
        ("get", "/api/studies/tiny.sqlite/results.xlsx", {}, 422),
        ("get", "/static/../_app.py", {}, 404),
        ("get", "/static/%2e%2e/_app.py", {}, 404),
        ("get", "/nowhere", {}, 404),
        ("get", "/api/assets", {}, 404),  # no --cps
        ("post", "/api/orders", {"json": {"object": "o1"}}, 404),
        ("delete", "/api/studies", {}, 405),
        ("get", "/api/studies/tiny.sqlite/analysis?object=o99", {}, 404),
        ("get", "/api/calibrations/nope", {}, 404),
        ("post", "/api/transfer", {"json": {"object": "o1"}}, 401),  # no token
        ("get", "/api/transfer/live?max_events=-1", {}, 422),
        ("put", "/api/transfer", {}, 405),
    ],
)  # fmt: skip
def test_bad_requests_get_4xx_with_a_message(client, method, path, kwargs, status):
    res = getattr(client, method)(path, **kwargs)
    assert res.status_code == status, res.text
    if res.headers.get("content-type", "").startswith("application/json"):
        assert res.json()["error"]
    assert "Traceback" not in res.text and 'File "' not in res.text


def test_states_and_best_worst_agree_with_the_rows(client, tiny_study):
    from scipy.stats import beta

    a = client.get("/api/studies/tiny.sqlite/analysis?object=o1").json()
    assert a["objects"] == ["o1"] and a["object"] == "o1"
    ok = [r for r in _rows(tiny_study) if r["status"] == "ok"]
    assert sum(s["n"] for s in a["states"]) == len(ok)
    for s in a["states"]:
        mine = [r for r in ok if (r["face"], r["conveyor"], r["theta_deg"]) ==
                (s["face"], s["conveyor"], s["theta_deg"])]  # fmt: skip
        k, n = sum(r["success"] for r in mine), len(mine)
        assert (s["k"], s["n"]) == (k, n)
        low = 0.0 if k == 0 else beta.ppf(0.025, k, n - k + 1)
        high = 1.0 if k == n else beta.ppf(0.975, k + 1, n - k)
        assert (s["low"], s["high"]) == pytest.approx((low, high))
    (sel,) = a["selection"]
    shares = [s["share"] for s in a["states"]]
    assert sel["best"]["share"] == max(shares) and sel["worst"]["share"] == min(shares)
    # what to do, in the report's words: decided level by level as far as the data decide
    from transfertwin.study.fullstate import decide_placement, placement_headline, state_table

    expected = placement_headline(decide_placement(state_table(ok), "o1"))
    assert sel["advice"] == expected and sel["advice"].startswith("Put it")
    assert client.get("/api/studies/tiny.sqlite/analysis").json() == a  # default: first core


def test_calibration_folders_are_listed_and_shown(tiny_study, tmp_path):
    folder = tmp_path / "cal"
    folder.mkdir()
    runs = [{"tp": 2, "fp": 1, "fn": 0, "tn": 1}]
    (folder / "metrics.json").write_text(json.dumps({"runs": runs, "mean": {
        "f05": 0.714, "precision": 0.667, "recall": 1.0, "accuracy": 0.75}}))  # fmt: skip
    (folder / "predictions.csv").write_text("object_id,success,pred_run0\n"
                                            "o1,1,1\no1,1,1\no2,0,1\no2,0,0\n")  # fmt: skip
    cfg = WebConfig(dbs=(tiny_study,), calibrations=(folder,))
    with TestClient(create_app(cfg), base_url=LOOPBACK, raise_server_exceptions=False) as c:
        assert c.get("/api/config").json()["calibrations"] == ["cal"]
        assert c.get("/api/calibrations").json() == {"calibrations": ["cal"]}
        v = c.get("/api/calibrations/cal").json()
        assert v["confusion"] == runs[0] and [s["object_id"] for s in v["shares"]] == ["o1", "o2"]
        assert v["shares"][1]["sim"]["k"] == 1 and v["f05"]["low"] is not None
        (folder / "predictions.csv").write_text("object_id,success,pred_run0\no1,1,7\n")
        res = c.get("/api/calibrations/cal")  # a folder that went bad: 4xx, no traceback
        assert res.status_code == 422 and "predictions.csv" in res.json()["error"]


def test_transfer_bodies_are_checked(client):
    token = client.app_state_token
    auth = {"Authorization": f"Bearer {token}"}
    for body in ({"object": "../../etc/passwd"}, {"object": "o1", "speed": 100},
                 {"object": "o1", "theta_deg": "x"}, {"object": "o1", "extra": 1}):  # fmt: skip
        res = client.post("/api/transfer", json=body, headers=auth)
        assert res.status_code == 422 and res.json()["error"], body
    res = client.post("/api/transfer", content=b"object=o1", headers={**auth,
                      "Content-Type": "text/plain"})  # fmt: skip
    assert res.status_code == 415
    assert client.get("/api/transfer").json()["run"] is None  # nothing started


def test_a_store_that_is_not_a_store_is_a_4xx(tmp_path):
    bogus = tmp_path / "bogus.sqlite"
    bogus.write_bytes(b"this is not sqlite at all" * 10)
    with TestClient(create_app(WebConfig(dbs=(bogus,))), base_url=LOOPBACK,
                    raise_server_exceptions=False) as c:  # fmt: skip
        res = c.get("/api/studies")
    assert 400 <= res.status_code < 500 and res.json()["error"]
    assert "Traceback" not in res.text


def test_off_loopback_every_request_needs_the_token(tiny_study):
    cfg = WebConfig(dbs=(tiny_study,), host="0.0.0.0", token="correct-horse-battery")
    with TestClient(create_app(cfg), base_url="http://10.0.0.5") as c:
        assert c.get("/").status_code == 401
        assert c.get("/api/studies").status_code == 401
        assert c.get("/api/studies", headers={"Authorization": "Bearer wrong-token"}
                     ).status_code == 401  # fmt: skip
        ok = c.get("/api/studies", headers={"Authorization": "Bearer correct-horse-battery"})
        assert ok.status_code == 200
        page = c.get("/?token=correct-horse-battery")  # sets an HttpOnly cookie
        assert page.status_code == 200 and "httponly" in page.headers["set-cookie"].lower()
        assert c.get("/api/studies").status_code == 200  # the cookie now authorises reads


def test_loopback_console_refuses_foreign_host_headers(client):
    res = client.get("/api/studies", headers={"Host": "evil.example"})
    assert res.status_code == 400  # DNS rebinding


def test_order_bodies_are_checked_before_anything_else(tiny_study, tmp_path):
    """Size, type and JSON shape are refused with 4xx (here without a CPS, so no order runs)."""
    cfg = WebConfig(dbs=(tiny_study,))
    with TestClient(create_app(cfg), base_url=LOOPBACK, raise_server_exceptions=False) as c:
        res = c.post("/api/orders", content=b"x" * (MAX_BODY_BYTES + 1),
                     headers={"Content-Type": "application/json"})  # fmt: skip
        assert res.status_code == 404  # no CPS: nothing is read at all


def test_cli_refuses_a_public_host_without_token():
    res = subprocess.run([sys.executable, "-m", "transfertwin", "web", "--host", "0.0.0.0"],
                         capture_output=True, text=True, timeout=120)  # fmt: skip
    assert res.returncode == 2
    assert len(res.stderr.strip().splitlines()) == 1 and "--token" in res.stderr


def test_cli_serves_until_sigterm(tiny_study, console_factory):
    import httpx

    console = console_factory("--db", str(tiny_study))
    assert console.base.startswith("http://127.0.0.1:")
    res = httpx.get(console.base + "/api/studies", timeout=30)
    assert res.status_code == 200 and res.json()["studies"][0]["done"] == 6
    console.stop()
    assert console.proc.returncode == 0


def _post_chunked(app, path: str, total: int, token: str | None = None,
                  length: int | None = None) -> tuple[int, int]:  # fmt: skip
    """POST a JSON body of `total` bytes in 64 KiB chunks straight to the ASGI app, as a
    chunked upload (or with a declared Content-Length `length`); (status, bytes the app
    took from the stream)."""
    import asyncio

    chunk = b" " * 65536
    left, taken, sent = total, 0, []

    async def receive():
        nonlocal left, taken
        if left <= 0:
            return {"type": "http.request", "body": b"", "more_body": False}
        part = chunk[: min(left, len(chunk))]
        left -= len(part)
        taken += len(part)
        return {"type": "http.request", "body": part, "more_body": left > 0}

    async def send(message):
        sent.append(message)

    headers = [(b"host", b"127.0.0.1"), (b"content-type", b"application/json")]
    headers.append((b"content-length", str(length).encode()) if length is not None
                   else (b"transfer-encoding", b"chunked"))  # fmt: skip
    if token is not None:
        headers.append((b"authorization", f"Bearer {token}".encode()))
    scope = {"type": "http", "asgi": {"version": "3.0"}, "http_version": "1.1",
             "method": "POST", "scheme": "http", "path": path, "raw_path": path.encode(),
             "query_string": b"", "root_path": "", "headers": headers,
             "client": ("127.0.0.1", 50000), "server": ("127.0.0.1", 80)}  # fmt: skip
    asyncio.run(app(scope, receive, send))
    return next(m["status"] for m in sent if m["type"] == "http.response.start"), taken


def test_a_large_body_without_token_is_refused_before_it_is_read(tiny_study, caplog):
    """64 MiB chunked to a write action with no token: 401 once the limit is passed, the
    rest never read, and the refusal in the audit log; declared too large: nothing read."""
    app = create_app(WebConfig(dbs=(tiny_study,)))
    with caplog.at_level("WARNING", logger="transfertwin.web.audit"):
        status, taken = _post_chunked(app, "/api/transfer", 64 * 2**20)
    assert status == 401
    assert taken <= MAX_BODY_BYTES + 65536  # the first chunk past the limit, no more
    assert any("starting a transfer refused: no valid token" in r.getMessage()
               for r in caplog.records)  # fmt: skip
    status, taken = _post_chunked(app, "/api/transfer", 64 * 2**20, length=64 * 2**20)
    assert (status, taken) == (401, 0)


def test_a_large_body_with_the_token_gets_413_as_soon_as_the_limit_is_passed(tiny_study, caplog):
    cfg = WebConfig(dbs=(tiny_study,))
    app = create_app(cfg)
    with caplog.at_level("WARNING", logger="transfertwin.web.audit"):
        status, taken = _post_chunked(app, "/api/transfer", 64 * 2**20, cfg.session_token)
    assert status == 413 and taken <= MAX_BODY_BYTES + 65536
    assert any("over" in r.getMessage() for r in caplog.records)
