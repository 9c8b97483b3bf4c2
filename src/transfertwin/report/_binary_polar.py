"""Result plot of the single experiments, state by state (Fig. 6.6/6.7).

The ``'ok'`` experiments of one object are counted per pre-transfer state, and each
state becomes one marker at its yaw θ on the polar axes of its face, coloured by its
success share k/n (red 0 … yellow 0.5 … green 1; a colour bar says so). One marker per
state, not one per experiment: dots of the repeated runs of a state would sit on the
same point and the last drawn (failure or success) would hide the others. With few
states per face (≤ `LABEL_MAX_STATES`) each marker is also labelled with its k/n.
For θ ∈ Θ_single the conveyor splits the ring: ``'left'`` on the outer ring,
``'right'`` on the inner ring; ``'both'`` states (θ ∈ Θ_both) sit between.
Marker shape also encodes the conveyor. Rows with another status are counted,
not drawn. θ = 0 is at the top and grows counter-clockwise, as in the
full-state plot. The rings are labelled with their conveyor on the plot and in the legend.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping
from dataclasses import dataclass

from matplotlib.cm import ScalarMappable
from matplotlib.colors import Normalize
from matplotlib.figure import Figure
from matplotlib.lines import Line2D

from transfertwin._errors import InputError
from transfertwin.ots import FACES
from transfertwin.report._figure import new_figure, setup_yaw_axes
from transfertwin.study.fullstate import ResultRecord, parse_row

__all__ = [
    "LABEL_MAX_STATES",
    "RING_RADIUS",
    "BinaryPoint",
    "BinaryPolar",
    "BinaryState",
    "binary_polar_data",
    "plot_binary_polar",
]

#: Radius of each conveyor's ring (outer 'left', inner 'right').
RING_RADIUS = {"left": 1.0, "both": 0.75, "right": 0.5}
_SHAPE = {"left": "^", "both": "o", "right": "v"}
#: Where each ring's label sits (θ, degrees): an angle whose states use another conveyor
#: (Eq. 6.7–6.10: left/right only for |θ| ≤ 25 or ≥ 155, both in between), so no marker
#: of that ring is ever hidden under its label.
RING_LABEL_DEG = {"left": 67, "both": 0, "right": -67}
#: Faces with at most this many run states get a k/n label at each marker.
LABEL_MAX_STATES = 16
#: Colour scale of the success share: red (0), yellow (0.5), green (1).
SHARE_CMAP = "RdYlGn"
_CONVEYORS = ("left", "both", "right")


@dataclass(frozen=True)
class BinaryPoint:
    """One experiment's marker.

    Attributes:
        face, conveyor, theta_deg: Its pre-transfer state.
        success: 1 or 0.
        radius: Ring radius from `RING_RADIUS`.
    """

    face: str
    conveyor: str
    theta_deg: int
    success: int
    radius: float


@dataclass(frozen=True)
class BinaryState:
    """One pre-transfer state's marker: its ``'ok'`` experiments and successes.

    Attributes:
        face, conveyor, theta_deg: The state.
        n, k: ``'ok'`` experiments (≥ 1) and successes among them.
        radius: Ring radius from `RING_RADIUS`.
    """

    face: str
    conveyor: str
    theta_deg: int
    n: int
    k: int
    radius: float

    @property
    def share(self) -> float:
        """Success share k/n (Eq. 6.26)."""
        return self.k / self.n


@dataclass(frozen=True)
class BinaryPolar:
    """Plot data of Fig. 6.7 for one object.

    Attributes:
        object_id: Object label.
        points: Markers of the ``'ok'`` experiments, in input order.
        n_excluded: Rows of the object with another status.
        states: The points counted per state (face, conveyor, θ), ordered by face,
            then ring (left, both, right), then θ; what the renderer draws.
    """

    object_id: str
    points: tuple[BinaryPoint, ...]
    n_excluded: int = 0
    states: tuple[BinaryState, ...] = ()

    def face_points(self, face: str) -> tuple[BinaryPoint, ...]:
        """Markers of one face."""
        return tuple(p for p in self.points if p.face == face)

    def face_states(self, face: str) -> tuple[BinaryState, ...]:
        """States of one face."""
        return tuple(s for s in self.states if s.face == face)

    @property
    def n_success(self) -> int:
        """Successful experiments drawn."""
        return sum(p.success for p in self.points)


def binary_polar_data(
    rows: Iterable[Mapping[str, object] | ResultRecord], object_id: str
) -> BinaryPolar:
    """Markers of one object's experiments (pure).

    Args:
        rows: Results-table rows (any object; others are ignored).
        object_id: The object to plot.

    Raises:
        InputError: On a bad row, or if the object has no row.
    """
    points, excluded, seen = [], 0, False
    for rec in map(parse_row, rows):
        if rec.object_id != object_id:
            continue
        seen = True
        if rec.status != "ok" or rec.success is None:
            excluded += 1
            continue
        radius = RING_RADIUS[rec.conveyor]
        points.append(BinaryPoint(rec.face, rec.conveyor, rec.theta_deg, rec.success, radius))
    if not seen:
        raise InputError(f"Fig. 6.7: no results for object {object_id!r}")
    return BinaryPolar(object_id, tuple(points), excluded, _per_state(points))


def _per_state(points: Iterable[BinaryPoint]) -> tuple[BinaryState, ...]:
    counts: dict[tuple[str, str, int], list[int]] = {}
    for p in points:
        nk = counts.setdefault((p.face, p.conveyor, p.theta_deg), [0, 0])
        nk[0] += 1
        nk[1] += p.success

    def order(key: tuple[str, str, int]) -> tuple[int, int, int]:
        face, conveyor, theta = key
        return (FACES.index(face), _CONVEYORS.index(conveyor), theta)

    return tuple(
        BinaryState(*key, n, k, RING_RADIUS[key[1]])
        for key, (n, k) in sorted(counts.items(), key=lambda kv: order(kv[0]))
    )


def _legend_handles() -> list[Line2D]:
    def handle(marker: str, color: str, label: str) -> Line2D:
        return Line2D([], [], linestyle="", marker=marker, color=color, label=label)

    ring = {"left": "outer ring", "both": "middle ring", "right": "inner ring"}
    return [handle(_SHAPE[c], "grey", f"{ring[c]}: conveyor c = {c}") for c in _CONVEYORS]


def _draw_states(ax, states: tuple[BinaryState, ...], norm: Normalize) -> None:
    """One marker per state, coloured by its share; k/n beside it when there are few."""
    for conveyor, marker in _SHAPE.items():
        sel = [s for s in states if s.conveyor == conveyor]
        if sel:
            ax.scatter(
                [math.radians(s.theta_deg) for s in sel], [s.radius for s in sel],
                c=[s.share for s in sel], cmap=SHARE_CMAP, norm=norm, s=70, marker=marker,
                edgecolors="#333333", linewidths=0.6, zorder=4,
            )  # fmt: skip
    if len(states) <= LABEL_MAX_STATES:
        for s in states:
            ax.text(
                math.radians(s.theta_deg), s.radius - 0.1, f"{s.k}/{s.n}", fontsize="x-small",
                ha="center", va="center", color="#222222", zorder=5,
            )  # fmt: skip


def plot_binary_polar(data: BinaryPolar, fig: Figure | None = None) -> Figure:
    """Draw Fig. 6.7 for one object: one polar axes per face.

    Args:
        data: From `binary_polar_data`.
        fig: Empty figure to draw into; a new 10 × 5 in figure when ``None``.

    Returns:
        The figure: two polar axes (one marker per state, coloured by k/n) and a
        colour bar of the success share.
    """
    fig = fig if fig is not None else new_figure(10.0, 5.2)
    norm = Normalize(0.0, 1.0)
    for i, face in enumerate(FACES):
        ax = fig.add_subplot(1, len(FACES), i + 1, projection="polar")
        setup_yaw_axes(ax)
        ax.set_rlim(0.0, 1.1)
        ax.set_yticks([RING_RADIUS[c] for c in ("right", "both", "left")], labels=[])
        for conveyor, theta in RING_LABEL_DEG.items():
            ax.text(
                math.radians(theta), RING_RADIUS[conveyor], f"c = {conveyor}",
                ha="center", va="center", fontsize="small", zorder=6,
                bbox={"boxstyle": "round,pad=0.15", "fc": "white", "ec": "#999999"},
            )  # fmt: skip
        ax.set_title(f"face '{face}'", pad=14)
        _draw_states(ax, data.face_states(face), norm)
    bar = fig.colorbar(ScalarMappable(norm, SHARE_CMAP), ax=fig.axes, shrink=0.6, pad=0.04)
    bar.set_label("success share k/n of the state")
    fig.legend(handles=_legend_handles(), loc="outside lower center", ncol=3, fontsize="small")
    n = len(data.points)
    title = (
        f"{data.object_id}: success share per state ({len(data.states)} states, "
        f"{n} experiments, {data.n_success} successful"
    )
    if data.n_excluded:
        title += f", {data.n_excluded} excluded"
    fig.suptitle(title + ")")
    return fig
