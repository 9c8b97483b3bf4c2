"""Full-state result plot of one object (Fig. 6.20/6.21): success rate over θ per face.

Data first: `polar_full_state_data` turns an object's series (Eq. 6.28) and its
selection (Alg. 1–4) into plain tuples; `plot_polar_full_state` draws them. Each
series (face × conveyor side: left conveyor c ∈ {left, both}, right conveyor
c ∈ {right, both}) gets its own polar axes, faces in rows and sides in columns, with
θ = 0 at the top, θ growing counter-clockwise and radius = success rate ∈ [0, 1]
(centre 0, rim 1). Own panels because the two sides share every 'both' state: at a
coarse θ-step (30°: only θ = 0 and 180 are single-conveyor) their curves coincide and
one would hide the other. The line is a circular-kernel estimate of the success
probability over θ (`circular_smooth`), the dots are the states' own rates k/n, and
the best (star) and worst (×) state of Alg. 1–4 sit at their ȳ^MA (Eq. 6.27), the
value the selection used, in the panel of the series they were chosen from. A spoke
from the centre to the rim at the state's θ, and its θ written as the tick label there
("best: θ = …°"), keep its angle readable even when it sits at radius 0.

The study's ȳ^MA averages the angles present within ±window/2; for sparse data
(e.g. the 191 real experiments, one per state) that is the raw 0/1 outcome of a
lone state, and joining such values by straight lines gives spikes through the
centre. The line drawn here is a Gaussian kernel on the circle instead, weighted by
each state's n, with bandwidth σ = max(window/2, a third of the median gap between run
angles); it is left out where no run angle lies within 2σ.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from matplotlib.figure import Figure

from transfertwin._errors import InputError
from transfertwin.ots import FACES
from transfertwin.report._figure import (
    FAILURE_COLOR,
    SUCCESS_COLOR,
    YAW_TICK_STEP_DEG,
    new_figure,
    setup_yaw_axes,
    signed_deg_label,
)
from transfertwin.study.fullstate import SelectedState, Selection, SeriesStats

__all__ = [
    "SMOOTH_GRID_DEG",
    "PolarCurve",
    "PolarFace",
    "PolarFullState",
    "PolarMarker",
    "circular_smooth",
    "plot_polar_full_state",
    "polar_full_state_data",
]


@dataclass(frozen=True)
class PolarCurve:
    """One smoothed series (Eq. 6.27) as plain numbers.

    Attributes:
        series: Series name, e.g. ``'front-left'``.
        side: ``'left'`` or ``'right'``.
        theta_deg: Angles, ascending, degrees.
        y_ma: ȳ^MA per angle (Eq. 6.27).
        n, k: Experiments and successes per angle.
        grid_deg: Angles of the smooth line, degrees.
        y_smooth: Circular-kernel estimate on the grid; NaN where no angle was run
            within 2σ.
        bandwidth_deg: Kernel σ, degrees.
    """

    series: str
    side: str
    theta_deg: tuple[int, ...]
    y_ma: tuple[float, ...]
    n: tuple[int, ...] = ()
    k: tuple[int, ...] = ()
    grid_deg: tuple[float, ...] = ()
    y_smooth: tuple[float, ...] = ()
    bandwidth_deg: float = math.nan

    @property
    def y_mean(self) -> tuple[float, ...]:
        """k/n per angle (Eq. 6.26)."""
        return tuple(k / n for k, n in zip(self.k, self.n, strict=True))


@dataclass(frozen=True)
class PolarMarker:
    """A selected state (Alg. 1–4) placed at (θ, ȳ^MA)."""

    kind: str
    series: str
    theta_deg: int
    y_ma: float


@dataclass(frozen=True)
class PolarFace:
    """Curves and markers of one face."""

    face: str
    curves: tuple[PolarCurve, ...]
    markers: tuple[PolarMarker, ...]


@dataclass(frozen=True)
class PolarFullState:
    """Plot data of Fig. 6.20/6.21 for one object: faces front, back."""

    object_id: str
    faces: tuple[PolarFace, ...]


def _marker(kind: str, state: SelectedState) -> PolarMarker:
    return PolarMarker(kind, state.series, state.theta_deg, state.y_ma)


#: Angles of the smooth lines: every degree, closed (-180 and 180 both present).
SMOOTH_GRID_DEG: tuple[float, ...] = tuple(float(t) for t in range(-180, 181))


def _wrapped_deg(d: np.ndarray) -> np.ndarray:
    """Angle differences wrapped into [-180, 180)."""
    return (d + 180.0) % 360.0 - 180.0


def _bandwidth(theta_deg: Sequence[int], window: int) -> float:
    """σ = max(window/2, a third of the median circular gap between the run angles)."""
    th = np.unique(np.asarray(theta_deg, dtype=float))
    if len(th) < 2:
        return window / 2.0
    gaps = np.diff(np.append(th, th[0] + 360.0))
    return max(window / 2.0, float(np.median(gaps)) / 3.0)


def circular_smooth(
    theta_deg: Sequence[float],
    k: Sequence[int],
    n: Sequence[int],
    sigma_deg: float,
    grid_deg: Sequence[float] = SMOOTH_GRID_DEG,
) -> np.ndarray:
    """Success probability over θ by a Gaussian kernel on the circle (pure).

    ŷ(φ) = Σ w_i k_i / Σ w_i n_i with w_i = exp(-d(φ, θ_i)² / 2σ²) and d the wrapped
    angle difference: a kernel regression of the states' rates weighted by their n.

    Args:
        theta_deg: Run angles (n_i ≥ 1), degrees.
        k, n: Successes and experiments per angle.
        sigma_deg: Kernel σ, degrees (> 0).
        grid_deg: Where to evaluate, degrees.

    Returns:
        ``(len(grid_deg),)`` estimates in [0, 1]; NaN where the nearest run angle is
        farther than 2σ (no data to speak of there).

    Raises:
        InputError: On mismatched lengths, n < 1, k outside [0, n] or σ ≤ 0.
    """
    th = np.asarray(theta_deg, dtype=float)
    kk, nn = np.asarray(k, dtype=float), np.asarray(n, dtype=float)
    if not (th.shape == kk.shape == nn.shape) or th.ndim != 1:
        raise InputError("circular_smooth: theta_deg, k and n need the same length")
    if (nn < 1).any() or (kk < 0).any() or (kk > nn).any() or not sigma_deg > 0:
        raise InputError("circular_smooth: need n >= 1, 0 <= k <= n and sigma > 0")
    grid = np.asarray(grid_deg, dtype=float)
    if th.size == 0:
        return np.full(grid.shape, np.nan)
    d = _wrapped_deg(grid[:, None] - th[None, :])
    w = np.exp(-0.5 * (d / sigma_deg) ** 2)
    with np.errstate(invalid="ignore", divide="ignore"):
        y = (w @ kk) / (w @ nn)
    y[np.abs(d).min(axis=1) > 2.0 * sigma_deg] = np.nan
    return y


def _curve(s: SeriesStats, window: int) -> PolarCurve:
    theta = tuple(s.theta_deg.tolist())
    n = tuple(st.n for st in s.states)
    k = tuple(st.k for st in s.states)
    sigma = _bandwidth(theta, window)
    smooth = circular_smooth(theta, k, n, sigma)
    return PolarCurve(
        s.name, s.side, theta, tuple(s.y_ma_array.tolist()), n, k,
        SMOOTH_GRID_DEG, tuple(smooth.tolist()), sigma,
    )  # fmt: skip


def polar_full_state_data(
    series: Sequence[SeriesStats], selection: Selection, *, window: int = 21
) -> PolarFullState:
    """Plot data for one object (pure).

    Args:
        series: The object's series from `series_table` (missing ones allowed).
        selection: Its best/worst state.
        window: The moving-average window of Eq. 6.27 (degrees); the smooth line's
            bandwidth is at least half of it.

    Raises:
        InputError: If a series belongs to another object than the selection.
    """
    obj = selection.object_id
    if any(s.object_id != obj for s in series):
        raise InputError(f"Fig. 6.20: series of another object than {obj!r}")
    faces = []
    for face in FACES:
        curves = tuple(_curve(s, window) for s in series if s.face == face)
        chosen = (("best", selection.best), ("worst", selection.worst))
        marks = tuple(_marker(kind, st) for kind, st in chosen if st.face == face)
        faces.append(PolarFace(face, curves, marks))
    return PolarFullState(obj, tuple(faces))


#: Per conveyor series: colour, line style and a label saying which states it holds.
_SERIES_STYLE = {
    "left": {"color": "#1f4e79", "linestyle": "-", "linewidth": 2.2},
    "right": {"color": "#e07b00", "linestyle": "--", "linewidth": 1.8},
}
_SERIES_LABEL = {
    "left": "left conveyor (c = left or both)",
    "right": "right conveyor (c = right or both)",
}
_MARK = {
    "best": {"marker": "*", "s": 300, "color": SUCCESS_COLOR, "edgecolors": "black"},
    "worst": {"marker": "X", "s": 150, "color": FAILURE_COLOR, "edgecolors": "black"},
}
#: What the radius means, written under each panel's title.
RADIUS_NOTE = "radius = success rate (centre 0, rim 1)"
#: Where the radius labels sit (degrees on the plot): between the 0° and 45° spokes.
RLABEL_DEG = 22.5


def _smooth_xy(curve: PolarCurve) -> tuple[np.ndarray, np.ndarray]:
    return np.radians(np.asarray(curve.grid_deg, dtype=float)), np.asarray(curve.y_smooth)


def _setup_rate_axes(ax) -> None:
    setup_yaw_axes(ax)
    ax.set_rlim(0.0, 1.05)
    ax.set_rticks([0.25, 0.5, 0.75, 1.0], labels=["0.25", "0.5", "0.75", ""])
    ax.set_rlabel_position(RLABEL_DEG)
    for label in ax.get_yticklabels():
        label.set_fontsize("small")
        label.set_color("#444444")
        label.set_bbox({"boxstyle": "round,pad=0.1", "fc": "white", "ec": "none", "alpha": 0.8})


def _draw_curve(ax, curve: PolarCurve) -> None:
    style = _SERIES_STYLE[curve.side]
    if curve.grid_deg:
        th, r = _smooth_xy(curve)
        ax.plot(th, r, label="smoothed success rate", zorder=3, **style)
    if curve.n:
        ax.scatter(
            np.radians(curve.theta_deg), curve.y_mean, s=18, color=style["color"],
            alpha=0.7, zorder=2, linewidths=0, label="each state's k/n",
        )  # fmt: skip


def _draw_marker(ax, m: PolarMarker) -> None:
    """The state at (θ, ȳ^MA) and a dotted spoke at its θ (visible at radius 0 too)."""
    th = math.radians(m.theta_deg)
    color = _MARK[m.kind]["color"]
    ax.plot([th, th], [0.0, 1.05], color=color, linestyle=":", linewidth=1.6, zorder=4)
    label = f"{m.kind} state: θ = {m.theta_deg}°, " + r"$\bar{y}^{MA}$" + f" = {m.y_ma:.2f}"
    ax.scatter([th], [m.y_ma], label=label, zorder=5, **_MARK[m.kind])


#: Grid ticks closer than this to a marked angle give way to its label, degrees.
_MARK_CLEARANCE_DEG = 15


def _label_marked_angles(ax, markers: Sequence[PolarMarker]) -> None:
    """Tick labels name the best/worst angle: ``'worst: θ = -150°'`` at the state's θ,
    framed in its colour; grid ticks within 15° of it are left out."""
    marks: dict[int, list[str]] = {}
    for m in markers:
        marks.setdefault(m.theta_deg, []).append(m.kind)
    if not marks:
        return
    far = [
        a for a in range(0, 360, YAW_TICK_STEP_DEG)
        if all(abs(_wrapped_deg(np.float64(a - t))) >= _MARK_CLEARANCE_DEG for t in marks)
    ]  # fmt: skip
    ticks = [(a, signed_deg_label(a), None) for a in far]
    ticks += [(t % 360, f"{', '.join(k)}: θ = {t}°", k[0]) for t, k in marks.items()]
    ticks.sort()
    ax.set_xticks(np.radians([a for a, _, _ in ticks]), labels=[lab for _, lab, _ in ticks])
    for label, (_, _, kind) in zip(ax.get_xticklabels(), ticks, strict=True):
        if kind is not None:
            label.set_fontweight("bold")
            label.set_bbox({"boxstyle": "round,pad=0.2", "fc": "white",
                            "ec": _MARK[kind]["color"]})  # fmt: skip


def plot_polar_full_state(data: PolarFullState, fig: Figure | None = None) -> Figure:
    """Draw Fig. 6.20/6.21 for one object: one polar axes per series (face × side).

    Args:
        data: From `polar_full_state_data`.
        fig: Empty figure to draw into; a new 11 × 11.5 in figure when ``None``.

    Returns:
        The figure: faces in rows, conveyor sides (left, right) in columns; a series
        with no run state leaves its panel empty.
    """
    fig = fig if fig is not None else new_figure(11.0, 11.5)
    sides = tuple(_SERIES_STYLE)
    for i, face in enumerate(data.faces):
        for j, side in enumerate(sides):
            ax = fig.add_subplot(len(data.faces), len(sides), i * len(sides) + j + 1,
                                 projection="polar")  # fmt: skip
            _setup_rate_axes(ax)
            ax.set_title(f"{face.face} face, {_SERIES_LABEL[side]}\n{RADIUS_NOTE}", pad=14)
            name = f"{face.face}-{side}"
            for curve in (c for c in face.curves if c.series == name):
                _draw_curve(ax, curve)
            marks = [m for m in face.markers if m.series == name]
            for m in marks:
                _draw_marker(ax, m)
            _label_marked_angles(ax, marks)
            if ax.get_legend_handles_labels()[0]:
                ax.legend(loc="upper center", bbox_to_anchor=(0.5, -0.1), fontsize="small")
    fig.suptitle(
        f"{data.object_id}: success rate over the yaw θ, one panel per face and conveyor "
        "(line: smoothed; dots: each state's k/n)"
    )
    return fig
