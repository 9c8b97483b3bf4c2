"""Per-state statistics (Eq. 6.26, Sec. 6.7), series (Eq. 6.21–6.24) and selection."""

from __future__ import annotations

import csv
import json
import math
from fractions import Fraction
from pathlib import Path

import numpy as np
import pytest

from transfertwin._errors import InputError
from transfertwin.study.fullstate import (
    STATES_COLUMNS,
    analyze,
    object_sort_key,
    parse_row,
    select,
    series_table,
    state_table,
)


def row(obj="o1", face="front", conveyor="both", theta=100, success=1, status="ok") -> dict:
    return {
        "object_id": obj,
        "face": face,
        "conveyor": conveyor,
        "theta_deg": theta,
        "success": success,
        "status": status,
    }


def scenario() -> list[dict]:
    """o1: front 'both' θ 100..140, successes exactly at 110..130 (two runs each);
    back 'left' θ -10..10 and back 'both' θ 40..60, all failures (one run each)."""
    rows = []
    for t in range(100, 141):
        rows += [row(theta=t, success=int(110 <= t <= 130))] * 2
    for t in range(-10, 11):
        rows.append(row(face="back", conveyor="left", theta=t, success=0))
    for t in range(40, 61):
        rows.append(row(face="back", theta=t, success=0))
    return rows


def test_eq_6_26_state_table_counts_only_ok_rows() -> None:
    rows = [
        row(success=1),
        row(success=1),
        row(success=0),
        row(success=None, status="invalid"),
        row(success=None, status="unstable"),
        row(success=1, status="error"),
        {k: v for k, v in row(theta=101, success="1").items() if k != "status"},
    ]
    stats = {s.theta_deg: s for s in state_table(rows)}
    s = stats[100]
    assert (s.n, s.k, s.n_invalid, s.n_unstable, s.n_error) == (3, 2, 1, 1, 1)
    assert s.y_mean == pytest.approx(2 / 3)
    # One success in one trial: Clopper–Pearson lower bound 0.025 (closed form).
    assert (stats[101].n, stats[101].k, stats[101].ci_low) == (1, 1, pytest.approx(0.025))


def test_sec_6_7_state_interval_closed_form() -> None:
    (s,) = state_table([row(success=1)] * 3)
    assert s.ci_low == pytest.approx(0.025 ** (1 / 3))
    assert s.ci_high == 1.0


def test_state_with_only_excluded_rows_has_n_zero_and_nan() -> None:
    (s,) = state_table([row(success=None, status="invalid")])
    assert (s.n, s.k, s.n_invalid) == (0, 0, 1)
    assert math.isnan(s.y_mean) and math.isnan(s.ci_low) and math.isnan(s.ci_high)


def test_state_table_is_in_natural_object_face_conveyor_theta_order() -> None:
    rows = [row(obj="o10"), row(obj="o2", face="back"), row(obj="o2", conveyor="both", theta=30)]
    rows.append(row(obj="o2", conveyor="left", theta=0))
    keys = [s.key for s in state_table(rows)]
    assert keys == [
        ("o2", "front", "left", 0),
        ("o2", "front", "both", 30),
        ("o2", "back", "both", 100),
        ("o10", "front", "both", 100),
    ]
    assert sorted(["o10", "o2", "o1"], key=object_sort_key) == ["o1", "o2", "o10"]


@pytest.mark.parametrize(
    ("bad", "message"),
    [
        (row(status="weird"), "status"),
        (row(face="side"), "face"),
        (row(conveyor="left", theta=90), r"Eq\. 6\.7"),
        (row(theta=200), "theta_deg"),
        (row(success=None), "success"),
        (row(success=2), "success"),
        (row(obj=" "), "object_id"),
        ({"object_id": "o1", "face": "front"}, "lacks column"),
    ],
)
def test_bad_rows_raise_input_error(bad: dict, message: str) -> None:
    with pytest.raises(InputError, match=message):
        parse_row(bad)


def test_eq_6_21_to_6_24_series_membership_and_skipping() -> None:
    stats = state_table(scenario())
    series = series_table(stats, "o1")
    assert [s.name for s in series] == ["front-left", "front-right", "back-left", "back-right"]
    front_left, _, back_left, back_right = series
    assert list(front_left.theta_deg) == list(range(100, 141))
    assert list(back_left.theta_deg) == [*range(-10, 11), *range(40, 61)]
    assert list(back_right.theta_deg) == list(range(40, 61))
    # Eq. 6.27 at θ=120: the window 110..130 holds only successes; at θ=100 the
    # present window 100..110 holds one success among 11 states.
    y_ma = dict(zip(front_left.theta_deg.tolist(), front_left.y_ma, strict=True))
    assert y_ma[120] == 1 and y_ma[119] == Fraction(20, 21) and y_ma[100] == Fraction(1, 11)
    only_front = [s for s in stats if s.face == "front"]
    assert [s.name for s in series_table(only_front, "o1")] == ["front-left", "front-right"]
    assert series_table(stats, "nobody") == ()


def test_alg_1_to_4_select_on_known_scenario() -> None:
    sel = select(state_table(scenario()), "o1")
    best, worst = sel.best, sel.worst
    # Best: unique maximum ȳ^MA = 1 at θ = 120 (h = 0); front-left precedes front-right.
    assert (best.face, best.conveyor, best.theta_deg, best.series) == (
        "front",
        "both",
        120,
        "front-left",
    )
    assert (best.y_ma, best.p_hat, best.n, best.k, best.half_window) == (1.0, 1.0, 2, 2, 0)
    assert best.ci_low == pytest.approx(0.025 ** (1 / 2))
    # Worst: back series are all zero -> ties survive to the full circle (h = 180),
    # lowest θ per series; back-left (θ = -10) precedes back-right (θ = 40).
    assert (worst.face, worst.conveyor, worst.theta_deg, worst.series) == (
        "back",
        "left",
        -10,
        "back-left",
    )
    assert (worst.y_ma, worst.p_hat, worst.half_window) == (0.0, 0.0, 180)


def test_select_unknown_object_raises() -> None:
    with pytest.raises(InputError, match="no state"):
        select(state_table(scenario()), "o99")


def test_analyze_writes_states_csv_and_selection_json(tmp_path: Path) -> None:
    rows = [
        *scenario(),
        row(obj="o2", theta=90, success=1),
        row(face="back", theta=41, success=None, status="error"),
    ]
    out = tmp_path / "new" / "dir"
    result = analyze(rows, out)
    assert result.object_ids == ("o1", "o2")
    with (out / "states.csv").open(newline="") as fh:
        lines = list(csv.reader(fh))
    assert (
        ",".join(lines[0])
        == "object_id,face,conveyor,theta_deg,n,k,y_mean,y_ma_left,y_ma_right,ci_low,ci_high"
    )
    assert tuple(lines[0]) == STATES_COLUMNS
    body = [dict(zip(lines[0], r, strict=True)) for r in lines[1:]]
    # One row per state: o1 41 front 'both' + 21 back 'left' + 21 back 'both'; o2 1 'both'.
    assert len(body) == 41 + 21 + 21 + 1
    keys = [(r["object_id"], r["face"], r["conveyor"], r["theta_deg"]) for r in body]
    assert len(set(keys)) == len(keys)
    r120 = [r for r in body if r["object_id"] == "o1" and r["theta_deg"] == "120"]
    assert len(r120) == 1
    assert float(r120[0]["y_ma_left"]) == float(r120[0]["y_ma_right"]) == 1.0
    assert r120[0]["n"] == "2" and r120[0]["k"] == "2"
    # A 'left' state is in the left series only.
    back_left = [r for r in body if r["face"] == "back" and r["conveyor"] == "left"]
    assert back_left and all(r["y_ma_left"] != "" and r["y_ma_right"] == "" for r in back_left)
    selection = json.loads((out / "selection.json").read_text())
    assert list(selection) == ["o1", "o2"]
    assert selection["o1"]["best"] == {
        "face": "front",
        "conveyor": "both",
        "theta_deg": 120,
        "y_ma": 1.0,
        "p_hat": 1.0,
        "n": 2,
        "ci_low": pytest.approx(0.025**0.5),
        "ci_high": 1.0,
        "half_window": 0,
    }
    assert selection["o1"]["worst"]["theta_deg"] == -10
    assert not list(out.glob("*.tmp"))


def test_analyze_writes_empty_fields_for_states_without_ok_rows(tmp_path: Path) -> None:
    analyze([row(success=1), row(theta=101, success=None, status="invalid")], tmp_path)
    with (tmp_path / "states.csv").open(newline="") as fh:
        body = list(csv.DictReader(fh))
    r101 = [r for r in body if r["theta_deg"] == "101"]
    assert len(r101) == 1
    assert all(
        r["n"] == "0" and r["y_mean"] == r["y_ma_left"] == r["y_ma_right"] == r["ci_low"] == ""
        for r in r101
    )


def test_analyze_bad_input_writes_nothing(tmp_path: Path) -> None:
    with pytest.raises(InputError):
        analyze([row(), row(face="upside")], tmp_path / "out")
    assert not (tmp_path / "out").exists()
    with pytest.raises(InputError, match="no experiment with status 'ok'"):
        analyze([row(success=None, status="invalid")], tmp_path / "out")
    assert not (tmp_path / "out").exists()


def test_bad_row_error_names_the_row_number() -> None:
    with pytest.raises(InputError, match=r"results row 2: theta_deg"):
        state_table([row(), row(theta=[1])])


def test_numpy_scalars_and_missing_status_are_accepted() -> None:
    rec = parse_row({**row(theta=np.int64(100), success=np.bool_(True)), "status": None})
    assert (rec.theta_deg, rec.success, rec.status) == (100, 1, "ok")
