"""Virtual against physical success probabilities per state (Fig. 6.24/6.25, Sec. 6.7).

`validation_plot_data` collects, for every compared state, p̂_V and p̂_P with
their Clopper–Pearson intervals and the Newcombe hybrid score interval of
p_V − p_P. `plot_validation` draws the two estimates side by side per state
(objects along x, states whose difference is significant on a red background,
as in Fig. 6.24/6.25) and, below, the difference intervals with a zero line.
`validate_and_report` runs `transfertwin.study.validation._validation.validate` and writes
its tables and ``validation.png``.
"""

from __future__ import annotations

import os
from collections import Counter
from collections.abc import Iterable, Mapping
from dataclasses import dataclass

import numpy as np
from matplotlib.axes import Axes
from matplotlib.figure import Figure

from transfertwin._errors import InputError
from transfertwin.report._figure import FAILURE_COLOR, figure_png, new_figure, write_atomic
from transfertwin.study.fullstate import ResultRecord, state_order
from transfertwin.study.validation import (
    StateComparison,
    ValidationResult,
    validate,
    write_validation,
)

__all__ = [
    "PHYSICAL_COLOR",
    "VALIDATION_FIGURE",
    "VIRTUAL_COLOR",
    "ValidationPlot",
    "plot_validation",
    "validate_and_report",
    "validation_plot_data",
]

VIRTUAL_COLOR = "#1f77b4"
PHYSICAL_COLOR = "#ff7f0e"
#: File name of the figure written by `validate_and_report`.
VALIDATION_FIGURE = "validation.png"
_SHIFT = 0.18  # horizontal offset of the two markers of one state


@dataclass(frozen=True)
class ValidationPlot:
    """Plot data of Fig. 6.24/6.25, one entry per compared state.

    Attributes:
        labels: x tick labels: the object id, with face, conveyor and θ added
            when the object has more than one compared state.
        object_ids: Object of each state.
        p_v, ci_v_low, ci_v_high, n_v: p̂_V, its Clopper–Pearson bounds and n.
        p_p, ci_p_low, ci_p_high, n_p: The same for the physical experiments.
        diff, diff_low, diff_high: p̂_V − p̂_P and its Newcombe hybrid score bounds.
        significant: Whether the difference interval excludes 0.
        alpha: 1 − confidence level.
        title: Figure title.
    """

    labels: tuple[str, ...]
    object_ids: tuple[str, ...]
    p_v: tuple[float, ...]
    ci_v_low: tuple[float, ...]
    ci_v_high: tuple[float, ...]
    n_v: tuple[int, ...]
    p_p: tuple[float, ...]
    ci_p_low: tuple[float, ...]
    ci_p_high: tuple[float, ...]
    n_p: tuple[int, ...]
    diff: tuple[float, ...]
    diff_low: tuple[float, ...]
    diff_high: tuple[float, ...]
    significant: tuple[bool, ...]
    alpha: float = 0.05
    title: str = "virtual vs physical success probability (cf. Fig. 6.24/6.25)"


def _label(c: StateComparison, several: bool) -> str:
    return f"{c.object_id} {c.face[0]}/{c.conveyor}/{c.theta_deg}°" if several else c.object_id


def validation_plot_data(
    comparisons: Iterable[StateComparison], title: str | None = None
) -> ValidationPlot:
    """Collect the estimates and intervals of every compared state (pure).

    Args:
        comparisons: From `compare` or `ValidationResult.comparisons`, e.g. only
            the best states (Fig. 6.24) or only the worst states (Fig. 6.25).
        title: Figure title; a default names the method.

    Raises:
        InputError: If there is no comparison or the alphas differ.
    """
    items = sorted(comparisons, key=lambda c: state_order(c.key))
    if not items:
        raise InputError("Fig. 6.24/6.25: no compared state to plot")
    alphas = {c.alpha for c in items}
    if len(alphas) > 1:
        raise InputError(f"Fig. 6.24/6.25: comparisons use different alphas {sorted(alphas)}")
    per_object = Counter(c.object_id for c in items)

    def col(name: str) -> tuple:
        return tuple(getattr(c, name) for c in items)

    return ValidationPlot(
        labels=tuple(_label(c, per_object[c.object_id] > 1) for c in items),
        object_ids=col("object_id"),
        p_v=col("p_v"), ci_v_low=col("ci_v_low"), ci_v_high=col("ci_v_high"), n_v=col("n_v"),
        p_p=col("p_p"), ci_p_low=col("ci_p_low"), ci_p_high=col("ci_p_high"), n_p=col("n_p"),
        diff=tuple(c.p_v - c.p_p for c in items),
        diff_low=col("diff_low"), diff_high=col("diff_high"), significant=col("significant"),
        alpha=alphas.pop(),
        title=title or "virtual vs physical success probability (cf. Fig. 6.24/6.25)",
    )  # fmt: skip


def _yerr(value: tuple[float, ...], low: tuple[float, ...], high: tuple[float, ...]) -> np.ndarray:
    v = np.asarray(value, dtype=float)
    return np.vstack([v - np.asarray(low, dtype=float), np.asarray(high, dtype=float) - v])


def _shade_significant(ax: Axes, data: ValidationPlot) -> None:
    for i, sig in enumerate(data.significant):
        if sig:
            ax.axvspan(i - 0.5, i + 0.5, color=FAILURE_COLOR, alpha=0.15, lw=0)


def _draw_probabilities(ax: Axes, data: ValidationPlot) -> None:
    x = np.arange(len(data.labels))
    conf = round(100 * (1 - data.alpha), 2)
    _shade_significant(ax, data)
    for shift, p, low, high, color, name in (
        (-_SHIFT, data.p_v, data.ci_v_low, data.ci_v_high, VIRTUAL_COLOR, "virtual"),
        (_SHIFT, data.p_p, data.ci_p_low, data.ci_p_high, PHYSICAL_COLOR, "physical"),
    ):
        ax.errorbar(x + shift, p, yerr=_yerr(p, low, high), fmt="o", color=color,
                    ecolor=color, capsize=3, elinewidth=1, label=name)  # fmt: skip
    ax.set_xlim(-0.5, len(x) - 0.5)
    ax.set_ylim(-0.05, 1.05)
    ax.set_ylabel(rf"$\hat{{p}}$, {conf:g} % Clopper–Pearson CI")
    ax.set_title(data.title, fontsize="medium")
    ax.grid(axis="y", alpha=0.3)
    ax.legend(loc="best", fontsize="small")


def _draw_difference(ax: Axes, data: ValidationPlot) -> None:
    x = np.arange(len(data.labels))
    colors = [FAILURE_COLOR if s else "black" for s in data.significant]
    err = _yerr(data.diff, data.diff_low, data.diff_high)
    _shade_significant(ax, data)
    ax.axhline(0.0, color="grey", lw=1)
    for i in range(len(x)):
        ax.errorbar(x[i], data.diff[i], yerr=err[:, i : i + 1], fmt="s", color=colors[i],
                    capsize=3, elinewidth=1)  # fmt: skip
    ax.set_xlim(-0.5, len(x) - 0.5)
    ax.set_ylim(-1.05, 1.05)
    ax.set_ylabel(r"$\hat{p}_V - \hat{p}_P$")
    ax.set_title("p_V − p_P, Newcombe hybrid score interval (red: excludes 0)", fontsize="medium")
    ax.grid(axis="y", alpha=0.3)


def plot_validation(
    data: ValidationPlot, fig: Figure | None = None, *, difference: bool = True
) -> Figure:
    """Draw Fig. 6.24/6.25: p̂_V and p̂_P with error bars per state, optionally the difference.

    Args:
        data: From `validation_plot_data`.
        fig: Empty figure to draw into; a new one (width grows with the states) when ``None``.
        difference: Also draw the Newcombe intervals of p_V − p_P below, with a zero line.

    Returns:
        The figure, with one or two axes sharing x.
    """
    n = len(data.labels)
    if fig is None:
        fig = new_figure(max(6.0, 0.4 * n + 2.0), 6.4 if difference else 3.8)
    top = fig.add_subplot(2 if difference else 1, 1, 1)
    _draw_probabilities(top, data)
    axes = [top]
    if difference:
        axes.append(fig.add_subplot(2, 1, 2, sharex=top))
        _draw_difference(axes[1], data)
    for ax in axes:
        ax.set_xticks(np.arange(n), labels=list(data.labels), rotation=90 if n > 12 else 0)
    if difference:
        top.tick_params(labelbottom=False)
    return fig


def validate_and_report(
    virtual: str | os.PathLike[str] | Iterable[Mapping[str, object] | ResultRecord],
    physical: str | os.PathLike[str] | Iterable[Mapping[str, object] | ResultRecord],
    out_dir: str | os.PathLike[str],
    *,
    alpha: float = 0.05,
) -> ValidationResult:
    """`validate` followed by the figure: writes tables and ``validation.png`` into ``out_dir``.

    Everything is read, computed and drawn before the first file is written, so
    bad input leaves no partial output; each file is written atomically.

    Args:
        virtual: Results of E^V (SQLite db, CSV or Parquet path, or rows).
        physical: Results of E^P, likewise.
        out_dir: Output folder, created if needed.
        alpha: 1 − confidence level of all intervals.

    Raises:
        InputError: As `validate`.
    """
    result = validate(virtual, physical, alpha=alpha)
    png = figure_png(plot_validation(validation_plot_data(result.comparisons)))
    out = write_validation(result, out_dir)
    write_atomic(out / VALIDATION_FIGURE, png)
    return result
