"""Plot data objects (pure) of Fig. 6.7, 6.20/6.21 and 6.22/6.23, exact values."""

from __future__ import annotations

import math

import pytest

from transfertwin._errors import InputError
from transfertwin.report import (
    RING_RADIUS,
    BinaryPoint,
    binary_polar_data,
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
        BinaryPoint("back", "right", -20, 0, 0.7),
        BinaryPoint("front", "both", 90, 0, 0.85),
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
