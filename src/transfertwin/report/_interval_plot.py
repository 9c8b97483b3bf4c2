"""Success probability with 95 % confidence intervals per object (Fig. 6.22/6.23).

`interval_plot_data` collects p̂ = k/n and the Clopper–Pearson bounds of every
object's best (Fig. 6.22) or worst (Fig. 6.23) state; `plot_intervals` draws
them as points with error bars, objects in natural order along x.
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass

import numpy as np
from matplotlib.axes import Axes
from matplotlib.figure import Figure

from transfertwin._errors import InputError
from transfertwin.report._figure import FAILURE_COLOR, SUCCESS_COLOR, new_figure
from transfertwin.study.fullstate import Selection, object_sort_key

__all__ = ["IntervalPlot", "interval_plot_data", "plot_intervals"]

_WHICH = ("best", "worst")


@dataclass(frozen=True)
class IntervalPlot:
    """Plot data of Fig. 6.22 (``which='best'``) or Fig. 6.23 (``'worst'``).

    Attributes:
        which: ``'best'`` or ``'worst'``.
        object_ids: Objects in natural order.
        p_hat: Estimated success probability per object.
        ci_low, ci_high: 95 % Clopper–Pearson bounds per object.
        n: Experiments behind each estimate.
    """

    which: str
    object_ids: tuple[str, ...]
    p_hat: tuple[float, ...]
    ci_low: tuple[float, ...]
    ci_high: tuple[float, ...]
    n: tuple[int, ...]


def interval_plot_data(selections: Iterable[Selection], which: str = "best") -> IntervalPlot:
    """Collect p̂ and its interval for every object's best or worst state (pure).

    Raises:
        InputError: If ``which`` is neither ``'best'`` nor ``'worst'``.
    """
    if which not in _WHICH:
        raise InputError(f"Fig. 6.22/6.23: which must be 'best' or 'worst', got {which!r}")
    ordered = sorted(selections, key=lambda s: object_sort_key(s.object_id))
    states = [getattr(s, which) for s in ordered]
    return IntervalPlot(
        which,
        tuple(s.object_id for s in ordered),
        tuple(st.p_hat for st in states),
        tuple(st.ci_low for st in states),
        tuple(st.ci_high for st in states),
        tuple(st.n for st in states),
    )


def plot_intervals(data: IntervalPlot, ax: Axes | None = None) -> Figure:
    """Draw Fig. 6.22/6.23: p̂ with 95 % error bars per object.

    Args:
        data: From `interval_plot_data`.
        ax: Axes to draw into; a new figure (width grows with the objects) when ``None``.

    Returns:
        The figure holding the axes.
    """
    if ax is None:
        fig = new_figure(max(6.0, 0.35 * len(data.object_ids) + 2.0), 3.6)
        ax = fig.add_subplot(1, 1, 1)
    x = np.arange(len(data.object_ids))
    p = np.asarray(data.p_hat, dtype=float)
    err = np.vstack([p - np.asarray(data.ci_low), np.asarray(data.ci_high) - p])
    color = SUCCESS_COLOR if data.which == "best" else FAILURE_COLOR
    ax.errorbar(x, p, yerr=err, fmt="o", color=color, ecolor="black", capsize=3, elinewidth=1)
    if len(x) <= 40:  # k/n next to each point while there is room
        for xi, pi, ni in zip(x, p, data.n, strict=True):
            ax.annotate(
                f"{round(pi * ni)}/{ni}", (xi, pi), xytext=(6, 0), textcoords="offset points",
                va="center", fontsize="small", color="#333333",
            )  # fmt: skip
    ax.set_xticks(x, labels=list(data.object_ids), rotation=90 if len(x) > 12 else 0)
    ax.set_xlim(-0.5, len(x) - 0.5 + 0.3)
    ax.set_ylim(-0.05, 1.05)
    ax.set_ylabel(r"success rate $\hat{p}$ = k/n, 95 % CI")
    fig_no = "6.22" if data.which == "best" else "6.23"
    ax.set_title(f"{data.which} state per object (cf. Fig. {fig_no}), Clopper–Pearson 95 %")
    ax.grid(axis="y", alpha=0.3)
    return ax.get_figure()
