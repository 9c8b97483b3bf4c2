"""Small multiples of a one-at-a-time sensitivity analysis: per factor, the simulated success
share against the factor's value with its Clopper–Pearson 95 % band, the stuck-at-gap share of
all experiments, and the real success share as a line. Data first (pure), then drawing."""

from __future__ import annotations

import math
from dataclasses import dataclass

from matplotlib.figure import Figure

from transfertwin.report._figure import FAILURE_COLOR, new_figure
from transfertwin.study.calibration import MorrisResult, SensitivityResult

__all__ = [
    "MorrisBar",
    "SensitivityPanel",
    "morris_plot_data",
    "plot_morris",
    "plot_sensitivity",
    "sensitivity_plot_data",
]


@dataclass(frozen=True)
class SensitivityPanel:
    """One factor's panel."""

    factor: str
    values: tuple[float, ...]
    share: tuple[float, ...]
    low: tuple[float, ...]
    high: tuple[float, ...]
    stuck_rate: tuple[float, ...]
    base_share: float
    real_share: float
    effect: float


def sensitivity_plot_data(result: SensitivityResult) -> tuple[SensitivityPanel, ...]:
    """One panel per factor, ordered by effect size (largest first)."""
    effects = {e["factor"]: float(e["share_range"]) for e in result.effects()}  # type: ignore[arg-type]
    real = float(result.real["share"])  # type: ignore[arg-type]
    panels = []
    for name in effects:
        lv = result.of(name)
        panels.append(
            SensitivityPanel(
                name,
                tuple(x.value for x in lv),
                tuple(x.share for x in lv),
                tuple(x.ci_low for x in lv),
                tuple(x.ci_high for x in lv),
                tuple(x.outcomes["stuck"] / x.n for x in lv),
                result.base.share,
                real,
                effects[name],
            )
        )
    return tuple(panels)


def plot_sensitivity(panels: tuple[SensitivityPanel, ...], title: str = "") -> Figure:
    """A grid of panels (up to 3 columns)."""
    n = max(1, len(panels))
    cols = min(3, n)
    rows = math.ceil(n / cols)
    fig = new_figure(4.0 * cols, 2.9 * rows)
    axes = fig.subplots(rows, cols, squeeze=False)
    for k, ax in enumerate(axes.flat):
        if k >= len(panels):
            ax.set_visible(False)
            continue
        p = panels[k]
        ax.fill_between(p.values, p.low, p.high, color="#1f77b4", alpha=0.2, lw=0)
        ax.plot(p.values, p.share, "o-", color="#1f77b4", label="sim success")
        ax.plot(p.values, p.stuck_rate, "s--", color=FAILURE_COLOR, ms=3,
                label="sim stuck at gap")  # fmt: skip
        ax.axhline(p.real_share, color="black", lw=1, label="real success")
        ax.axhline(p.base_share, color="grey", lw=0.8, ls=":", label="base profile")
        ax.set_ylim(-0.02, 1.02)
        ax.set_title(f"{p.factor} (Δ {p.effect:.2f})", fontsize=9)
        ax.tick_params(labelsize=7)
        if k == 0:
            ax.legend(fontsize=6, loc="lower left")
    if title:
        fig.suptitle(title, fontsize=10)
    return fig


@dataclass(frozen=True)
class MorrisBar:
    """One factor's Morris indices for one output."""

    factor: str
    mu_star: float
    mu_star_conf: float
    sigma: float


def morris_plot_data(result: MorrisResult, output: str = "share") -> tuple[MorrisBar, ...]:
    """The factors by mu* of `output`, largest first."""
    return tuple(
        MorrisBar(str(r["factor"]), float(r["mu_star"]), float(r["mu_star_conf"]),  # type: ignore[arg-type]
                  float(r["sigma"]))  # type: ignore[arg-type]
        for r in result.ranking(output)
    )  # fmt: skip


def plot_morris(bars: tuple[MorrisBar, ...], title: str = "") -> Figure:
    """Horizontal bars of mu* (with its bootstrap confidence) and sigma per factor."""
    fig = new_figure(6.5, 0.45 * max(3, len(bars)) + 1.0)
    ax = fig.subplots()
    y = list(range(len(bars)))[::-1]
    ax.barh([v + 0.2 for v in y], [b.mu_star for b in bars], height=0.4,
            xerr=[b.mu_star_conf for b in bars], color="#1f77b4", label="mu*")  # fmt: skip
    ax.barh([v - 0.2 for v in y], [b.sigma for b in bars], height=0.4, color="#ff7f0e",
            label="sigma")  # fmt: skip
    ax.set_yticks(y, [b.factor for b in bars], fontsize=8)
    ax.set_xlabel("elementary effect on the success share")
    ax.legend(fontsize=7)
    if title:
        ax.set_title(title, fontsize=10)
    return fig
