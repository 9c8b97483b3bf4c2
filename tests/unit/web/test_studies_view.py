"""The console's study figures: progress (rate, ETA) and the success map, from plain rows."""

from __future__ import annotations

from datetime import UTC, datetime, timedelta

import pytest

from transfertwin._errors import InputError
from transfertwin.report import RING_RADIUS
from transfertwin.web import RATE_WINDOW, WebConfig, is_loopback, progress_of, success_map

T0 = datetime(2026, 1, 1, tzinfo=UTC)


def test_rate_and_eta_from_finish_times():
    times = [T0 + timedelta(seconds=2 * i) for i in range(11)]  # 10 intervals in 20 s
    p = progress_of(11, 111, times, {"ok": 11}, now=T0 + timedelta(seconds=25))
    assert p["rate_per_s"] == pytest.approx(0.5)
    assert p["eta_s"] == pytest.approx(100 / 0.5)
    assert p["fraction"] == pytest.approx(11 / 111)
    assert p["idle_s"] == pytest.approx(5.0)


def test_rate_uses_only_the_latest_window():
    slow = [T0 + timedelta(seconds=100 * i) for i in range(50)]
    fast_start = slow[-1] + timedelta(seconds=100)
    fast = [fast_start + timedelta(seconds=i) for i in range(RATE_WINDOW)]
    p = progress_of(150, 1000, slow + fast, {})
    assert p["rate_per_s"] == pytest.approx(1.0)


def test_no_rate_without_two_distinct_times_and_no_eta_when_done():
    assert progress_of(1, 10, [T0], {})["rate_per_s"] is None
    assert progress_of(2, 10, [T0, T0], {})["eta_s"] is None
    done = progress_of(2, 2, [T0, T0 + timedelta(seconds=1)], {})
    assert done["eta_s"] == 0.0 and done["fraction"] == 1.0
    unknown = progress_of(2, None, [T0, T0 + timedelta(seconds=1)], {})
    assert unknown["eta_s"] is None and unknown["fraction"] is None


def _row(obj, face, conveyor, theta, success, status="ok"):
    return {"object_id": obj, "face": face, "conveyor": conveyor, "theta_deg": theta,
            "success": success, "status": status}  # fmt: skip


def test_success_map_shares_per_state_and_excluded_rows():
    rows = [
        _row("o1", "front", "left", 30, 1),
        _row("o1", "front", "left", 30, 0),
        _row("o1", "front", "left", 30, 1),
        _row("o1", "back", "both", -90, 0),
        _row("o1", "back", "both", -90, None, status="unstable"),
        _row("o2", "front", "right", 0, None, status="error"),
    ]
    m = success_map(rows)
    assert m["faces"] == ["front", "back"]
    (cell,) = m["objects"]["o1"]["front"]
    assert (cell["n"], cell["successes"]) == (3, 2)
    assert cell["share"] == pytest.approx(2 / 3)
    assert cell["r"] == RING_RADIUS["left"]
    (back,) = m["objects"]["o1"]["back"]
    assert (back["theta_deg"], back["conveyor"], back["share"]) == (-90, "both", 0.0)
    assert m["excluded"] == {"o1": 1, "o2": 1}
    assert m["objects"]["o2"] == {"front": [], "back": []}


@pytest.mark.parametrize(
    ("host", "loopback"),
    [("127.0.0.1", True), ("127.5.0.1", True), ("::1", True), ("localhost", True),
     ("0.0.0.0", False), ("192.168.1.2", False), ("example.org", False), ("::", False)],
)  # fmt: skip
def test_loopback_detection(host, loopback):
    assert is_loopback(host) is loopback


def test_off_loopback_needs_a_token_and_a_random_one_is_made_on_loopback():
    with pytest.raises(InputError, match="--token"):
        WebConfig(host="0.0.0.0")
    assert WebConfig(host="0.0.0.0", token="s3cret-token").reads_need_token
    a, b = WebConfig(), WebConfig()
    assert len(a.session_token) >= 20 and a.session_token != b.session_token
    assert not a.reads_need_token
