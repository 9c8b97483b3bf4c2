"""Binary result plot of single experiments (Fig. 6.6/6.7).

Every ``'ok'`` experiment of one object becomes a marker at its yaw θ on the
polar axes of its face, green for success (y = 1) and red for failure (y = 0).
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

from matplotlib.figure import Figure
from matplotlib.lines import Line2D

from transfertwin._errors import InputError
from transfertwin.ots import FACES
from transfertwin.report._figure import FAILURE_COLOR, SUCCESS_COLOR, new_figure, setup_yaw_axes
from transfertwin.study.fullstate import ResultRecord, parse_row

__all__ = ["RING_RADIUS", "BinaryPoint", "BinaryPolar", "binary_polar_data", "plot_binary_polar"]

#: Radius of each conveyor's ring (outer 'left', inner 'right').
RING_RADIUS = {"left": 1.0, "both": 0.75, "right": 0.5}
_SHAPE = {"left": "^", "both": "o", "right": "v"}
#: Where each ring's label sits (θ, degrees): an angle whose states use another conveyor
#: (Eq. 6.7–6.10: left/right only for |θ| ≤ 25 or ≥ 155, both in between), so no marker
#: of that ring is ever hidden under its label.
RING_LABEL_DEG = {"left": 67, "both": 0, "right": -67}


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
class BinaryPolar:
    """Plot data of Fig. 6.7 for one object.

    Attributes:
        object_id: Object label.
        points: Markers of the ``'ok'`` experiments, in input order.
        n_excluded: Rows of the object with another status.
    """

    object_id: str
    points: tuple[BinaryPoint, ...]
    n_excluded: int = 0

    def face_points(self, face: str) -> tuple[BinaryPoint, ...]:
        """Markers of one face."""
        return tuple(p for p in self.points if p.face == face)

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
    return BinaryPolar(object_id, tuple(points), excluded)


def _legend_handles() -> list[Line2D]:
    def handle(marker: str, color: str, label: str) -> Line2D:
        return Line2D([], [], linestyle="", marker=marker, color=color, label=label)

    handles = [
        handle("o", SUCCESS_COLOR, "success (y=1)"),
        handle("o", FAILURE_COLOR, "failure (y=0)"),
    ]
    ring = {"left": "outer ring", "both": "middle ring", "right": "inner ring"}
    handles += [
        handle(_SHAPE[c], "grey", f"{ring[c]}: conveyor c = {c}") for c in ("left", "both", "right")
    ]
    return handles


def plot_binary_polar(data: BinaryPolar, fig: Figure | None = None) -> Figure:
    """Draw Fig. 6.7 for one object: one polar axes per face.

    Args:
        data: From `binary_polar_data`.
        fig: Empty figure to draw into; a new 10 × 5 in figure when ``None``.

    Returns:
        The figure (two polar axes). Failures are drawn over successes.
    """
    fig = fig if fig is not None else new_figure(10.0, 5.2)
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
        pts = data.face_points(face)
        for success in (1, 0):
            color = SUCCESS_COLOR if success else FAILURE_COLOR
            for conveyor, marker in _SHAPE.items():
                sel = [p for p in pts if p.success == success and p.conveyor == conveyor]
                if sel:
                    th = [math.radians(p.theta_deg) for p in sel]
                    ax.scatter(th, [p.radius for p in sel], s=28, c=color, marker=marker)
    fig.legend(handles=_legend_handles(), loc="outside lower center", ncol=3, fontsize="small")
    n = len(data.points)
    title = f"{data.object_id}: {n} experiments, {data.n_success} successful"
    if data.n_excluded:
        title += f", {data.n_excluded} excluded"
    fig.suptitle(title)
    return fig
