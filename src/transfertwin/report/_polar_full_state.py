"""Full-state result plot of one object (Fig. 6.20/6.21): ȳ^MA over θ per face.

Data first: `polar_full_state_data` turns an object's series (Eq. 6.28) and its
selection (Alg. 1–4) into plain tuples; `plot_polar_full_state` draws them. Each
face gets a polar axes with θ = 0 at the top, θ growing counter-clockwise and
radius ȳ^MA ∈ [0, 1]; the left series is thick dashed, the right series thin
dotted; the best state is a star, the worst an ×.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from matplotlib.figure import Figure

from transfertwin._errors import InputError
from transfertwin.ots import FACES
from transfertwin.report._figure import FAILURE_COLOR, SUCCESS_COLOR, new_figure, setup_yaw_axes
from transfertwin.study.fullstate import SelectedState, Selection, SeriesStats

__all__ = [
    "PolarCurve",
    "PolarFace",
    "PolarFullState",
    "PolarMarker",
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
        y_ma: ȳ^MA per angle.
    """

    series: str
    side: str
    theta_deg: tuple[int, ...]
    y_ma: tuple[float, ...]


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


def polar_full_state_data(series: Sequence[SeriesStats], selection: Selection) -> PolarFullState:
    """Plot data for one object (pure).

    Args:
        series: The object's series from `series_table` (missing ones allowed).
        selection: Its best/worst state.

    Raises:
        InputError: If a series belongs to another object than the selection.
    """
    obj = selection.object_id
    if any(s.object_id != obj for s in series):
        raise InputError(f"Fig. 6.20: series of another object than {obj!r}")
    faces = []
    for face in FACES:
        curves = tuple(
            PolarCurve(s.name, s.side, tuple(s.theta_deg.tolist()), tuple(s.y_ma_array.tolist()))
            for s in series
            if s.face == face
        )
        chosen = (("best", selection.best), ("worst", selection.worst))
        marks = tuple(_marker(kind, st) for kind, st in chosen if st.face == face)
        faces.append(PolarFace(face, curves, marks))
    return PolarFullState(obj, tuple(faces))


_LINE = {
    "left": {"linestyle": "--", "linewidth": 2.4},
    "right": {"linestyle": ":", "linewidth": 1.2},
}
_MARK = {
    "best": {"marker": "*", "s": 260, "color": SUCCESS_COLOR},
    "worst": {"marker": "x", "s": 120, "color": FAILURE_COLOR},
}


def _closed(theta_deg: tuple[int, ...], y: tuple[float, ...]) -> tuple[np.ndarray, np.ndarray]:
    th, r = np.radians(theta_deg), np.asarray(y, dtype=float)
    if len(th) > 1 and theta_deg[0] == -179 and theta_deg[-1] == 180:
        th, r = np.append(th, th[0] + 2 * math.pi), np.append(r, r[0])
    return th, r


def plot_polar_full_state(data: PolarFullState, fig: Figure | None = None) -> Figure:
    """Draw Fig. 6.20/6.21 for one object: one polar axes per face.

    Args:
        data: From `polar_full_state_data`.
        fig: Empty figure to draw into; a new 10 × 5 in figure when ``None``.

    Returns:
        The figure (two polar axes).
    """
    fig = fig if fig is not None else new_figure(10.0, 5.2)
    for i, face in enumerate(data.faces):
        ax = fig.add_subplot(1, len(data.faces), i + 1, projection="polar")
        setup_yaw_axes(ax)
        ax.set_rlim(0.0, 1.0)
        ax.set_title(f"f = '{face.face}'")
        for curve in face.curves:
            th, r = _closed(curve.theta_deg, curve.y_ma)
            dots = "." if len(curve.theta_deg) < 360 else ""  # sparse series: show the data
            style = _LINE[curve.side]
            ax.plot(th, r, color="#1f4e79", marker=dots, label=curve.series, **style)
        for m in face.markers:
            label = f"{m.kind} ({m.theta_deg}°)"
            ax.scatter(
                [math.radians(m.theta_deg)], [m.y_ma], label=label, zorder=5, **_MARK[m.kind]
            )
        if face.curves or face.markers:
            ax.legend(loc="lower left", bbox_to_anchor=(-0.15, -0.18), fontsize="small")
    fig.suptitle(f"{data.object_id}: smoothed success rate " + r"$\bar{y}^{MA}$ over $\theta$")
    return fig
