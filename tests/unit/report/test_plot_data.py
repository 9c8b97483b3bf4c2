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
    SMOOTH_MIN_N,
    BinaryPoint,
    binary_polar_data,
    circular_smooth,
    interval_plot_data,
    polar_full_state_data,
)
from transfertwin.study.fullstate import (
    SelectedState,
    Selection,
    select,
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


def test_full_state_data_has_one_panel_per_face_and_conveyor() -> None:
    stats = state_table(scenario())
    data = polar_full_state_data([s for s in stats if s.object_id == "o1"], select(stats, "o1"))
    assert data.object_id == "o1"
    assert [(p.face, p.conveyor) for p in data.panels] == [
        ("front", "left"), ("front", "both"), ("front", "right"),
        ("back", "left"), ("back", "both"), ("back", "right"),
    ]  # fmt: skip
    both = data.panel("front", "both")
    assert both.theta_deg == tuple(range(100, 141)) and set(both.n) == {1}
    assert both.y_mean == tuple(float(110 <= t <= 130) for t in range(100, 141))
    # Clopper-Pearson 95 % of 1/1 is [0.025, 1] and of 0/1 [0, 0.975] (exact: 0.05/2).
    i = both.theta_deg.index(120)
    assert (both.ci_low[i], both.ci_high[i]) == pytest.approx((0.025, 1.0))
    assert data.panel("front", "left").theta_deg == ()  # nothing run there
    assert data.panel("back", "left").theta_deg == tuple(range(-10, 11))
    # Markers sit at the state's own k/n in its conveyor's panel (Alg. 1-4: best θ 120).
    assert [(m.kind, m.theta_deg, m.p_hat) for m in both.markers] == [("best", 120, 1.0)]
    assert [(m.kind, m.theta_deg) for m in data.panel("back", "left").markers] == [("worst", -10)]


def test_full_state_data_rejects_states_of_another_object() -> None:
    stats = state_table([*scenario(), row(obj="o2")])
    with pytest.raises(InputError, match="another object"):
        polar_full_state_data(stats, select(stats, "o1"))


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


def _real_o1():
    path = Path(__file__).parents[3] / "src" / "transfertwin" / "data"
    with (path / "calibration_experiments.csv").open(newline="") as fh:
        stats = state_table(list(csv.DictReader(fh)))
    return polar_full_state_data([s for s in stats if s.object_id == "o1"], select(stats, "o1"))


def test_no_smoothed_line_where_n_does_not_support_one() -> None:
    """The 191 real experiments hold one run per state: no panel gets a line; its states
    are drawn as they are."""
    data = _real_o1()
    assert sum(sum(p.n) for p in data.panels) == 54
    assert not any(p.smoothed for p in data.panels)


def test_a_smoothed_line_only_where_enough_runs_lie_under_the_kernel() -> None:
    rows = [row(theta=t, success=int(r < 6)) for t in range(30, 151, 5) for r in range(8)]
    rows += [row(face="back", theta=t, success=1) for t in range(30, 151, 30) for _ in range(4)]
    stats = state_table(rows)
    data = polar_full_state_data(stats, select(stats, "o1"))
    dense, sparse = data.panel("front", "both"), data.panel("back", "both")
    line = np.asarray(dense.y_smooth)
    assert dense.smoothed and np.allclose(line[np.isfinite(line)], 0.75)
    assert np.isfinite(line[180 + 90]) and np.isnan(line[180 - 90])  # only near the runs
    assert not sparse.smoothed  # 4 runs a state, 30° apart: under 10 runs near any angle
    assert SMOOTH_MIN_N == 10.0
    y = circular_smooth([0, 30], [4, 4], [4, 4], 10.5, grid_deg=[0.0], min_n=10.0)
    assert np.isnan(y[0])  # 4 + 4 * exp(-0.5 (30/10.5)^2) = 4.07 runs under the kernel
    y = circular_smooth([0, 30], [4, 4], [4, 4], 10.5, grid_deg=[0.0], min_n=4.0)
    assert y[0] == 1.0
