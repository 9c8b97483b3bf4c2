"""Fidelity plots of a twin against real outcomes: reliability curve, precision–recall
curve, and per-object success share simulated vs real with Clopper–Pearson intervals.
Data first (pure, tested), then drawing."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np
from matplotlib.figure import Figure
from sklearn.metrics import precision_recall_curve

from transfertwin.report._figure import new_figure
from transfertwin.study.fullstate import clopper_pearson

__all__ = [
    "Curve",
    "FidelityPlot",
    "ShareBar",
    "fidelity_plot_data",
    "plot_fidelity",
]


@dataclass(frozen=True)
class Curve:
    """One predictor's curve: x, y (same length) and its label."""

    label: str
    x: tuple[float, ...]
    y: tuple[float, ...]
    counts: tuple[int, ...] = ()


@dataclass(frozen=True)
class ShareBar:
    """Per object: real and simulated success share, each with its 95 % interval."""

    object_id: str
    real: float
    real_low: float
    real_high: float
    sim: float
    sim_low: float
    sim_high: float


@dataclass(frozen=True)
class FidelityPlot:
    """Everything the three panels draw."""

    reliability: tuple[Curve, ...]
    pr: tuple[Curve, ...]
    shares: tuple[ShareBar, ...]
    base_rate: float


def _reliability(label: str, p: np.ndarray, y: np.ndarray, bins: int) -> Curve:
    edges = np.linspace(0.0, 1.0, bins + 1)
    idx = np.clip(np.digitize(p, edges[1:-1]), 0, bins - 1)
    xs, ys, ns = [], [], []
    for b in range(bins):
        m = idx == b
        if m.any():
            xs.append(float(p[m].mean()))
            ys.append(float(y[m].mean()))
            ns.append(int(m.sum()))
    return Curve(label, tuple(xs), tuple(ys), tuple(ns))


def fidelity_plot_data(
    y: np.ndarray,
    predictions: Mapping[str, np.ndarray],
    objects: np.ndarray,
    sim_successes: Mapping[str, tuple[int, int]],
    *,
    bins: int = 5,
) -> FidelityPlot:
    """Curves per predictor and per-object shares.

    Args:
        y: Real outcomes (n,).
        predictions: Label → P(success) per real row (n,), e.g. the twin held out.
        objects: Object id per row (n,).
        sim_successes: Object id → (successful, valid) simulated runs over its real rows.
        bins: Equal-width probability bins of the reliability curve.
    """
    y = np.asarray(y, dtype=int)
    rel, pr = [], []
    for label, p in predictions.items():
        p = np.asarray(p, dtype=float)
        rel.append(_reliability(label, p, y, bins))
        precision, recall, _ = precision_recall_curve(y, p)
        pr.append(Curve(label, tuple(map(float, recall)), tuple(map(float, precision))))
    shares = []
    for obj in sorted(sim_successes, key=lambda o: (len(o), o)):
        m = objects == obj
        k_real, n_real = int(y[m].sum()), int(m.sum())
        k_sim, n_sim = sim_successes[obj]
        ri, si = clopper_pearson(k_real, n_real), clopper_pearson(k_sim, n_sim)
        sim = k_sim / n_sim if n_sim else float("nan")
        shares.append(ShareBar(obj, k_real / n_real, ri.low, ri.high, sim, si.low, si.high))
    return FidelityPlot(tuple(rel), tuple(pr), tuple(shares), float(y.mean()))


def plot_fidelity(data: FidelityPlot, fig: Figure | None = None) -> Figure:
    """Three panels: reliability, precision–recall, per-object share (real vs simulated)."""
    fig = fig or new_figure(13.5, 4.2)
    ax_rel, ax_pr, ax_sh = fig.subplots(1, 3)
    ax_rel.plot([0, 1], [0, 1], color="0.6", linestyle=":", label="perfectly calibrated")
    for c in data.reliability:
        ax_rel.plot(c.x, c.y, marker="o", label=c.label)
    ax_rel.set(xlabel="predicted P(success)", ylabel="observed success share",
               title="reliability", xlim=(0, 1), ylim=(0, 1.02))  # fmt: skip
    for c in data.pr:
        ax_pr.step(c.x, c.y, where="post", label=c.label)
    ax_pr.axhline(data.base_rate, color="0.6", linestyle=":", label="always success")
    ax_pr.set(xlabel="recall", ylabel="precision", title="precision–recall",
              xlim=(0, 1), ylim=(0, 1.02))  # fmt: skip
    _draw_shares(ax_sh, data.shares)
    for ax in (ax_rel, ax_pr, ax_sh):
        ax.grid(alpha=0.3)
        ax.legend(loc="lower left", fontsize=8)
    return fig


def _draw_shares(ax, shares: Sequence[ShareBar]) -> None:
    x = np.arange(len(shares))
    for dx, attr, label in ((-0.12, "real", "real"), (0.12, "sim", "twin")):
        mid = np.array([getattr(s, attr) for s in shares])
        low = np.array([getattr(s, f"{attr}_low") for s in shares])
        high = np.array([getattr(s, f"{attr}_high") for s in shares])
        ax.errorbar(x + dx, mid, yerr=[mid - low, high - mid], fmt="o", capsize=4, label=label)
    ax.set_xticks(x, [s.object_id for s in shares])
    ax.set(ylabel="success share (95 % Clopper–Pearson)", title="per object", ylim=(0, 1.02))
