"""Figure plumbing shared by the renderers: pyplot-free figures, PNG bytes, atomic files.

Figures are `matplotlib.figure.Figure` objects built without pyplot, so no global
state or GUI backend is touched; saving to PNG uses the Agg canvas.
"""

from __future__ import annotations

import io

import numpy as np
from matplotlib.axes import Axes
from matplotlib.figure import Figure

from transfertwin._atomic import write_atomic

__all__ = [
    "FAILURE_COLOR",
    "SUCCESS_COLOR",
    "figure_png",
    "new_figure",
    "setup_yaw_axes",
    "write_atomic",
]

SUCCESS_COLOR = "#2ca02c"
FAILURE_COLOR = "#d62728"


def new_figure(width_in: float, height_in: float) -> Figure:
    """A fresh pyplot-free figure of the given size, inches."""
    return Figure(figsize=(width_in, height_in), layout="constrained")


def setup_yaw_axes(ax: Axes) -> None:
    """Polar axes for yaw θ: 0° at the top, counter-clockwise, labels in -135..180°."""
    ax.set_theta_zero_location("N")
    ax.set_theta_direction(1)
    angles = np.arange(0, 360, 45)
    labels = [f"{a if a <= 180 else a - 360}°" for a in angles]
    ax.set_xticks(np.radians(angles), labels=labels)


def figure_png(fig: Figure, dpi: int = 100) -> bytes:
    """The figure rendered as PNG bytes."""
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=dpi)
    return buf.getvalue()
