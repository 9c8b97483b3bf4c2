"""Full-state result plot of one object (after Fig. 6.20/6.21): success over θ per state.

Data first: `polar_full_state_data` turns an object's per-state counts (`StateStat`,
Eq. 6.26) and its selection (Alg. 1–4) into one `PolarPanel` per face and conveyor value
(left, both, right: six panels), and `plot_polar_full_state` draws them, faces in rows and
conveyors in columns, with θ = 0 at the top, θ growing counter-clockwise and radius =
success share in [0, 1] (centre 0, rim 1).

What the data hold comes first: every run state is a dot at its own share k/n with its
95 % Clopper–Pearson interval as a radial bar, in the panel of its own conveyor (a state
centred across both belts is not drawn again in the left and right panels, as the study's
series of Eq. 6.21–6.24 would have it). A smoothed line is added only where the counts
support it: a Gaussian kernel on the circle over the panel's states, weighted by their n
(`circular_smooth`), with bandwidth σ = max(window/2, a third of the median gap between
run angles), drawn only where at least `SMOOTH_MIN_N` experiments lie under the kernel
(Σ wᵢnᵢ) and some run angle within 2σ. With a few runs per state (the tutorial's 4) no
line is drawn: its lobes and zeros would be the work of two or three states. The best
(star) and worst (×) state of Alg. 1–4 sit at their own k/n in their conveyor's panel, a
dotted spoke and a tick label ("best: θ = …°") keeping their angle readable at radius 0.
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
from transfertwin.study.fullstate import SelectedState, Selection, StateStat

__all__ = [
    "PANEL_CONVEYORS",
    "SMOOTH_GRID_DEG",
    "SMOOTH_MIN_N",
    "PolarFullState",
    "PolarMarker",
    "PolarPanel",
    "circular_smooth",
    "plot_polar_full_state",
    "polar_full_state_data",
]

#: Column order of the panels: the conveyor values as seen from the TM, left to right.
PANEL_CONVEYORS = ("left", "both", "right")
#: The smoothed line is drawn only where at least this many experiments lie under the
#: kernel (Σ wᵢnᵢ): below it the line would follow single states' 0/1 outcomes.
SMOOTH_MIN_N = 10.0
#: Angles of the smooth lines: every degree, closed (-180 and 180 both present).
SMOOTH_GRID_DEG: tuple[float, ...] = tuple(float(t) for t in range(-180, 181))


@dataclass(frozen=True)
class PolarMarker:
    """A selected state (Alg. 1–4) placed at (θ, k/n) in its conveyor's panel."""

    kind: str
    conveyor: str
    theta_deg: int
    p_hat: float


@dataclass(frozen=True)
class PolarPanel:
    """The run states of one face and conveyor value, as plain numbers.

    Attributes:
        face, conveyor: The panel.
        theta_deg: Run angles, ascending, degrees.
        k, n: Successes and ``'ok'`` experiments per angle.
        ci_low, ci_high: Clopper–Pearson 95 % bounds per angle.
        grid_deg: Angles of the smooth line, degrees (`SMOOTH_GRID_DEG`).
        y_smooth: Kernel estimate on the grid; NaN where fewer than `SMOOTH_MIN_N`
            experiments lie under the kernel or no run angle within 2σ (all NaN: no line).
        bandwidth_deg: Kernel σ, degrees.
        markers: The best/worst state when it lies in this panel.
    """

    face: str
    conveyor: str
    theta_deg: tuple[int, ...]
    k: tuple[int, ...]
    n: tuple[int, ...]
    ci_low: tuple[float, ...]
    ci_high: tuple[float, ...]
    grid_deg: tuple[float, ...]
    y_smooth: tuple[float, ...]
    bandwidth_deg: float
    markers: tuple[PolarMarker, ...] = ()

    @property
    def y_mean(self) -> tuple[float, ...]:
        """k/n per angle (Eq. 6.26)."""
        return tuple(k / n for k, n in zip(self.k, self.n, strict=True))

    @property
    def smoothed(self) -> bool:
        """Whether any part of the smooth line is drawn."""
        return any(math.isfinite(y) for y in self.y_smooth)


@dataclass(frozen=True)
class PolarFullState:
    """Plot data for one object: panels face by face (front, back), conveyors left, both,
    right within a face."""

    object_id: str
    panels: tuple[PolarPanel, ...]

    def panel(self, face: str, conveyor: str) -> PolarPanel:
        """The panel of (face, conveyor)."""
        return next(p for p in self.panels if (p.face, p.conveyor) == (face, conveyor))


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
    *,
    min_n: float = 0.0,
) -> np.ndarray:
    """Success probability over θ by a Gaussian kernel on the circle (pure).

    ŷ(φ) = Σ w_i k_i / Σ w_i n_i with w_i = exp(-d(φ, θ_i)² / 2σ²) and d the wrapped
    angle difference: a kernel regression of the states' rates weighted by their n.

    Args:
        theta_deg: Run angles (n_i ≥ 1), degrees.
        k, n: Successes and experiments per angle.
        sigma_deg: Kernel σ, degrees (> 0).
        grid_deg: Where to evaluate, degrees.
        min_n: Leave out grid points where Σ w_i n_i, the experiments under the kernel,
            is below this.

    Returns:
        ``(len(grid_deg),)`` estimates in [0, 1]; NaN where the nearest run angle is
        farther than 2σ (no data to speak of there) or fewer than `min_n` experiments
        lie under the kernel.

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
    y[(w @ nn) < min_n] = np.nan
    return y


def _panel(face: str, conveyor: str, states: Sequence[StateStat], window: int,
           markers: tuple[PolarMarker, ...]) -> PolarPanel:  # fmt: skip
    run = sorted((s for s in states if (s.face, s.conveyor) == (face, conveyor) and s.n > 0),
                 key=lambda s: s.theta_deg)  # fmt: skip
    theta = tuple(s.theta_deg for s in run)
    k, n = tuple(s.k for s in run), tuple(s.n for s in run)
    sigma = _bandwidth(theta, window)
    smooth = circular_smooth(theta, k, n, sigma, min_n=SMOOTH_MIN_N)
    return PolarPanel(
        face, conveyor, theta, k, n, tuple(s.ci_low for s in run),
        tuple(s.ci_high for s in run), SMOOTH_GRID_DEG, tuple(smooth.tolist()), sigma,
        tuple(m for m in markers if m.conveyor == conveyor),
    )  # fmt: skip


def _marker(kind: str, state: SelectedState) -> PolarMarker:
    return PolarMarker(kind, state.conveyor, state.theta_deg, state.p_hat)


def polar_full_state_data(
    states: Sequence[StateStat], selection: Selection, *, window: int = 21
) -> PolarFullState:
    """Plot data for one object (pure): six panels, face × conveyor.

    Args:
        states: The object's per-state statistics (`state_table`; n = 0 states ignored).
        selection: Its best/worst state (Alg. 1–4).
        window: The moving-average window of Eq. 6.27 (degrees); the smooth line's
            bandwidth is at least half of it.

    Raises:
        InputError: If a state belongs to another object than the selection.
    """
    obj = selection.object_id
    if any(s.object_id != obj for s in states):
        raise InputError(f"full-state plot: states of another object than {obj!r}")
    panels = []
    for face in FACES:
        chosen = (("best", selection.best), ("worst", selection.worst))
        marks = tuple(_marker(kind, st) for kind, st in chosen if st.face == face)
        panels += [_panel(face, c, states, window, marks) for c in PANEL_CONVEYORS]
    return PolarFullState(obj, tuple(panels))


#: Panel titles: the conveyor value in words.
PANEL_TITLE = {
    "left": "on the left belt",
    "both": "centred across both belts",
    "right": "on the right belt",
}
_STATE_COLOR = "#1f4e79"
_SMOOTH_STYLE = {"color": "#7f7f7f", "linestyle": "--", "linewidth": 1.6}
_MARK = {
    "best": {"marker": "*", "s": 300, "color": SUCCESS_COLOR, "edgecolors": "black"},
    "worst": {"marker": "X", "s": 150, "color": FAILURE_COLOR, "edgecolors": "black"},
}
#: What the radius means, written under each panel's title.
RADIUS_NOTE = "radius = success share (centre 0, rim 1)"
#: Where the radius labels sit (degrees on the plot): between the 0° and 45° spokes.
RLABEL_DEG = 22.5
#: Up to this many states in a panel, each is labelled with its k/n.
_LABEL_MAX = 12


def _setup_rate_axes(ax) -> None:
    setup_yaw_axes(ax)
    ax.set_rlim(0.0, 1.05)
    ax.set_rticks([0.25, 0.5, 0.75, 1.0], labels=["0.25", "0.5", "0.75", ""])
    ax.set_rlabel_position(RLABEL_DEG)
    for label in ax.get_yticklabels():
        label.set_fontsize("small")
        label.set_color("#444444")
        label.set_bbox({"boxstyle": "round,pad=0.1", "fc": "white", "ec": "none", "alpha": 0.8})


def _draw_states(ax, p: PolarPanel) -> None:
    """Each state's k/n (dot) and 95 % interval (radial bar); k/n written when few."""
    th = np.radians(p.theta_deg)
    for t, lo, hi in zip(th, p.ci_low, p.ci_high, strict=True):
        ax.plot([t, t], [lo, hi], color=_STATE_COLOR, alpha=0.45, linewidth=2.5, zorder=2)
    ax.scatter(th, p.y_mean, s=26, color=_STATE_COLOR, zorder=3,
               label="each state's k/n with its 95 % interval")  # fmt: skip
    if len(p.theta_deg) <= _LABEL_MAX:
        for t, y, k, n in zip(th, p.y_mean, p.k, p.n, strict=True):
            ax.annotate(f"{k}/{n}", (t, y), xytext=(4, 4), textcoords="offset points",
                        fontsize="small", color=_STATE_COLOR)  # fmt: skip


def _draw_smooth(ax, p: PolarPanel) -> None:
    if not p.smoothed:
        return
    label = (f"smoothed over θ (kernel σ = {p.bandwidth_deg:.3g}°), where ≥ "
             f"{SMOOTH_MIN_N:g} runs lie under it")  # fmt: skip
    th = np.radians(np.asarray(p.grid_deg, dtype=float))
    ax.plot(th, np.asarray(p.y_smooth), label=label, zorder=1, **_SMOOTH_STYLE)


def _draw_marker(ax, m: PolarMarker) -> None:
    """The state at (θ, k/n) and a dotted spoke at its θ (visible at radius 0 too)."""
    th = math.radians(m.theta_deg)
    color = _MARK[m.kind]["color"]
    ax.plot([th, th], [0.0, 1.05], color=color, linestyle=":", linewidth=1.6, zorder=4)
    label = f"{m.kind} state of Alg. 1–4: θ = {m.theta_deg}°, k/n = {m.p_hat:.2f}"
    ax.scatter([th], [m.p_hat], label=label, zorder=5, **_MARK[m.kind])


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


def _panel_title(p: PolarPanel) -> str:
    if not p.n:
        return f"{p.face} face, {PANEL_TITLE[p.conveyor]}\nnot run"
    runs = f"{sum(p.n)} runs at {len(p.n)} angle{'s' if len(p.n) > 1 else ''}"
    return f"{p.face} face, {PANEL_TITLE[p.conveyor]}\n{runs}"


def plot_polar_full_state(data: PolarFullState, fig: Figure | None = None) -> Figure:
    """Draw one object's states: one polar axes per face (rows) and conveyor (columns).

    Args:
        data: From `polar_full_state_data`.
        fig: Empty figure to draw into; a new 15 × 11 in figure when ``None``.

    Returns:
        The figure: six polar axes titled by face and conveyor; a panel with no run
        state is left empty and says "not run".
    """
    fig = fig if fig is not None else new_figure(15.0, 11.0)
    cols = len(PANEL_CONVEYORS)
    for i, p in enumerate(data.panels):
        ax = fig.add_subplot(len(data.panels) // cols, cols, i + 1, projection="polar")
        _setup_rate_axes(ax)
        ax.set_title(_panel_title(p), pad=14)
        if p.n:
            _draw_smooth(ax, p)
            _draw_states(ax, p)
        for m in p.markers:
            _draw_marker(ax, m)
        _label_marked_angles(ax, p.markers)
        if ax.get_legend_handles_labels()[0]:
            ax.legend(loc="upper center", bbox_to_anchor=(0.5, -0.1), fontsize="small")
    fig.suptitle(
        f"{data.object_id}: success share of each pre-transfer state over the yaw θ, "
        f"one panel per face and conveyor\n(dot: k/n; bar: 95 % interval; {RADIUS_NOTE})"
    )
    return fig
