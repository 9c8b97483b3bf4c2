"""Score distributions of parameter studies (Fig. 6.12/6.14): data first, then drawing."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from matplotlib.figure import Figure

__all__ = ["ScoreDistribution", "plot_score_distribution", "score_distribution_data"]


@dataclass(frozen=True)
class ScoreDistribution:
    """Per parameter set: its label and the metric of every calibration run."""

    labels: tuple[str, ...]
    scores: tuple[tuple[float, ...], ...]
    metric: str

    @property
    def means(self) -> tuple[float, ...]:
        """Mean score per set."""
        return tuple(float(np.mean(s)) for s in self.scores)


def score_distribution_data(
    labels: Sequence[str], scores: Sequence[Sequence[float]], metric: str = "f05"
) -> ScoreDistribution:
    """Bundle labelled per-run scores (one sequence per parameter set)."""
    if len(labels) != len(scores):
        raise ValueError("one score list per label")
    return ScoreDistribution(
        tuple(labels), tuple(tuple(float(v) for v in s) for s in scores), metric
    )


def plot_score_distribution(data: ScoreDistribution, fig: Figure | None = None) -> Figure:
    """Box plot with an overlaid violin per parameter set and the mean as a red cross."""
    fig = fig or Figure(figsize=(max(5.0, 0.9 * len(data.labels) + 2), 4.0))
    ax = fig.add_subplot(1, 1, 1)
    positions = np.arange(1, len(data.labels) + 1)
    spread = [list(s) for s in data.scores]
    if any(len(set(s)) > 1 for s in spread):
        ax.violinplot(spread, positions=positions, showextrema=False)
    ax.boxplot(spread, positions=positions, widths=0.35)
    ax.plot(positions, data.means, "rx", markersize=9, label="mean")
    ax.set_xticks(positions, data.labels, rotation=30, ha="right")
    ax.set_ylabel(data.metric.replace("f05", "F0.5"))
    ax.set_ylim(0.0, 1.0)
    ax.grid(axis="y", alpha=0.3)
    ax.legend(loc="lower right")
    fig.tight_layout()
    return fig
