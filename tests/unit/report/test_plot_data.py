"""Plot data objects (pure) of Fig. 6.7, 6.20/6.21 and 6.22/6.23, exact values."""

from __future__ import annotations

import csv
import math
from pathlib import Path

import numpy as np
import pytest

from transfertwin._errors import InputError
from transfertwin.report import (
    RING_RADIUS,
    BinaryPoint,
    BinaryState,
    binary_polar_data,
    circular_smooth,
    interval_plot_data,
    polar_full_state_data,
)
from transfertwin.study.fullstate import (
    SelectedState,
    Selection,
    select,
    series_table,
    state_table,
)


def row(obj="o1", face="front", conveyor="both", theta=100, success=1, status="ok") -> dict:
    return dict(
        object_id=obj, face=face, conveyor=conveyor, theta_deg=theta, success=success, status=status
    )


def scenario() -> list[dict]:
    """Front 'both' θ 100..140 with successes at 110..130; back 'left' θ -10..10 failures."""
    rows = [row(theta=t, success=int(110 <= t <= 130)) for t in range(100, 141)]
    return rows + [row(face="back", conveyor="left", theta=t, success=0) for t in range(-10, 11)]


def state(theta: int, p: float, low: float, high: float, n: int) -> SelectedState:
    return SelectedState("front", "both", theta, "front-left", p, p, n, round(p * n), low, high, 0)


def test_fig_6_20_polar_full_state_data() -> None:
    stats = state_table(scenario())
    data = polar_full_state_data(series_table(stats, "o1"), select(stats, "o1"))
    front, back = data.faces
    assert (data.object_id, front.face, back.face) == ("o1", "front", "back")
    assert [c.series for c in front.curves] == ["front-left", "front-right"]
    assert [(c.series, c.side) for c in back.curves] == [("back-left", "left")]
    curve = front.curves[0]
    assert curve.theta_deg == tuple(range(100, 141))
    # Eq. 6.27 by hand: θ=120 sees 21 successes; θ=119 sees 20 of 21; θ=100 sees 1 of 11.
    y = dict(zip(curve.theta_deg, curve.y_ma, strict=True))
    assert (y[120], y[119], y[100]) == (1.0, 20 / 21, 1 / 11)
    assert [(m.kind, m.theta_deg, m.y_ma) for m in front.markers] == [("best", 120, 1.0)]
    assert [(m.kind, m.theta_deg, m.y_ma) for m in back.markers] == [("worst", -10, 0.0)]


def test_fig_6_20_rejects_series_of_another_object() -> None:
    stats = state_table([*scenario(), row(obj="o2")])
    with pytest.raises(InputError, match="another object"):
        polar_full_state_data(series_table(stats, "o2"), select(stats, "o1"))


def test_fig_6_7_binary_polar_data() -> None:
    rows = [
        row(theta=-20, conveyor="left", success=1),
        row(theta=-20, conveyor="right", success=0, face="back"),
        row(theta=90, success=0),
        row(theta=91, success=None, status="invalid"),
        row(obj="o2", theta=5, conveyor="left", success=1),
    ]
    data = binary_polar_data(rows, "o1")
    assert data.points == (
        BinaryPoint("front", "left", -20, 1, 1.0),
        BinaryPoint("back", "right", -20, 0, 0.5),
        BinaryPoint("front", "both", 90, 0, 0.75),
    )
    assert (data.n_excluded, data.n_success) == (1, 1)
    assert [p.theta_deg for p in data.face_points("front")] == [-20, 90]
    assert RING_RADIUS["left"] > RING_RADIUS["both"] > RING_RADIUS["right"]
    with pytest.raises(InputError, match="no results"):
        binary_polar_data(rows, "o3")


def test_fig_6_22_interval_plot_data_natural_order() -> None:
    sels = [
        Selection("o10", state(5, 1.0, 0.93, 1.0, 50), state(7, 0.0, 0.0, 0.07, 50)),
        Selection("o2", state(3, 0.5, 0.36, 0.64, 50), state(4, 0.1, 0.03, 0.22, 50)),
    ]
    best = interval_plot_data(sels, "best")
    assert best.object_ids == ("o2", "o10")
    assert (best.p_hat, best.ci_low, best.ci_high, best.n) == (
        (0.5, 1.0),
        (0.36, 0.93),
        (0.64, 1.0),
        (50, 50),
    )
    worst = interval_plot_data(sels, "worst")
    assert (worst.which, worst.p_hat) == ("worst", (0.1, 0.0))
    with pytest.raises(InputError, match="best' or 'worst"):
        interval_plot_data(sels, "median")
    assert math.isclose(sum(best.p_hat), 1.5)


def test_circular_smooth_is_a_kernel_mean_on_the_circle() -> None:
    # Constant rate -> the same constant everywhere near data.
    y = circular_smooth([0, 90, 180, -90], [3, 3, 3, 3], [4, 4, 4, 4], 30.0)
    assert np.allclose(y[np.isfinite(y)], 0.75) and np.isfinite(y).all()
    # Wraps: 179 and -179 are neighbours, so the value at 180 is their n-weighted mean.
    y = circular_smooth([179, -179], [1, 0], [3, 1], 5.0, grid_deg=[180.0])
    assert y[0] == pytest.approx(1 / 4)
    # Far from every run angle (> 2 sigma) there is no estimate.
    y = circular_smooth([0], [1], [1], 10.0, grid_deg=[15.0, 25.0])
    assert y[0] == 1.0 and math.isnan(y[1])
    with pytest.raises(InputError):
        circular_smooth([0], [2], [1], 10.0)


def test_full_state_line_of_sparse_real_data_is_smooth() -> None:
    """The 191 real experiments (one per state): the drawn line has no 0-1 spikes."""
    path = Path(__file__).parents[3] / "src" / "transfertwin" / "data"
    with (path / "calibration_experiments.csv").open(newline="") as fh:
        real = list(csv.DictReader(fh))
    stats = state_table(real)
    data = polar_full_state_data(series_table(stats, "o1"), select(stats, "o1"))
    raw_jumps = []
    for curve in (c for face in data.faces for c in face.curves):
        y = np.asarray(curve.y_smooth)
        assert len(y) == 361 and np.nanmax(y) <= 1.0 and np.nanmin(y) >= 0.0
        steps = np.abs(np.diff(y))  # 1° apart; NaN where the line has a gap
        assert np.nanmax(steps) < 0.1
        raw_jumps.append(np.max(np.abs(np.diff(curve.y_ma))))
    # The ȳ^MA values of the same states, joined state to state, jump from 0 to 1.
    assert max(raw_jumps) == 1.0


def test_fig_6_7_one_share_per_state_not_one_dot_per_experiment() -> None:
    """Issue 30.1: o32 front θ = -60 with 6 of 8 successes is one state at share 0.75."""
    rows = [row(obj="o32", theta=-60, success=int(r < 6)) for r in range(8)]
    rows += [row(obj="o32", theta=-60, success=None, status="unstable")]
    rows += [row(obj="o32", theta=0, conveyor="left", success=0) for _ in range(3)]
    rows += [row(obj="o32", theta=0, conveyor="right", success=1)]
    data = binary_polar_data(rows, "o32")
    assert data.states == (
        BinaryState("front", "left", 0, 3, 0, RING_RADIUS["left"]),
        BinaryState("front", "both", -60, 8, 6, RING_RADIUS["both"]),
        BinaryState("front", "right", 0, 1, 1, RING_RADIUS["right"]),
    )
    assert [s.share for s in data.face_states("front")] == [0.0, 0.75, 1.0]
    assert data.face_states("back") == ()
