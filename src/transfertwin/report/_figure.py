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
    "YAW_TICK_STEP_DEG",
    "figure_png",
    "new_figure",
    "setup_yaw_axes",
    "signed_deg_label",
    "write_atomic",
    "yaw_tick_labels",
]

SUCCESS_COLOR = "#2ca02c"
FAILURE_COLOR = "#d62728"


def new_figure(width_in: float, height_in: float) -> Figure:
    """A fresh pyplot-free figure of the given size, inches."""
    return Figure(figsize=(width_in, height_in), layout="constrained")


#: Spacing of the yaw ticks, degrees: the study's coarse θ-steps (30, 60) land on ticks.
YAW_TICK_STEP_DEG = 30


def signed_deg_label(angle_deg: int) -> str:
    """An angle written in the project's signed convention θ ∈ -179..180: ``'-150°'`` for
    210 (or -150), ``'180°'`` for -180."""
    a = angle_deg % 360
    return f"{a if a <= 180 else a - 360}°"


def yaw_tick_labels(step_deg: int = YAW_TICK_STEP_DEG) -> list[str]:
    """Tick labels of the polar yaw axes at 0, step, … < 360 degrees on the plot, signed
    (`signed_deg_label`)."""
    return [signed_deg_label(a) for a in range(0, 360, step_deg)]


def setup_yaw_axes(ax: Axes) -> None:
    """Polar axes for yaw θ: 0° at the top, counter-clockwise, signed labels every 30°."""
    ax.set_theta_zero_location("N")
    ax.set_theta_direction(1)
    angles = np.arange(0, 360, YAW_TICK_STEP_DEG)
    ax.set_xticks(np.radians(angles), labels=yaw_tick_labels())


def figure_png(fig: Figure, dpi: int = 100) -> bytes:
    """The figure rendered as PNG bytes."""
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=dpi)
    return buf.getvalue()
