"""Real vs synthetic docking errors: histograms (Fig. 6.9/6.11a) and correlations (Fig. 6.10/6.11b).

`docking_hist_data` bins the real and the synthetic errors on shared edges as densities
(the samples differ in size); `docking_correlation_data` computes both 3×3 Pearson
correlation matrices. The renderers draw them into pyplot-free figures. Inputs are
(n, 3) arrays of x (mm), y (mm) and θ (deg).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from matplotlib.figure import Figure

from transfertwin._errors import InputError
from transfertwin.report._figure import new_figure

__all__ = [
    "DOCKING_LABELS",
    "DockingCorrelations",
    "DockingHistograms",
    "docking_correlation_data",
    "docking_hist_data",
    "plot_correlation_matrices",
    "plot_docking_histograms",
]

#: Axis labels of the components e_x, e_y, e_θ with their units.
DOCKING_LABELS = ("e_x [mm]", "e_y [mm]", "e_θ [deg]")
_REAL, _SYNTH = "#1f77b4", "#ff7f0e"

Matrix = tuple[tuple[float, ...], ...]


def _errors(values: np.ndarray, what: str) -> np.ndarray:
    x = np.asarray(values, dtype=float)
    if x.ndim != 2 or x.shape[1] != 3 or x.shape[0] < 2:
        raise InputError(f"{what} docking errors: expected an (n >= 2, 3) array, got {x.shape}")
    if not np.all(np.isfinite(x)):
        raise InputError(f"{what} docking errors: values must be finite")
    return x


def _rows(a: np.ndarray) -> Matrix:
    return tuple(tuple(float(v) for v in r) for r in a)


@dataclass(frozen=True)
class DockingHistograms:
    """Plot data of Fig. 6.9/6.11a.

    Attributes:
        labels: Component labels with units.
        edges: Shared bin edges per component (bins + 1 each), data units.
        real, synthetic: Density per bin (integrates to 1 over the edges) per component.
        n_real, n_synthetic: Sample sizes.
    """

    labels: tuple[str, ...]
    edges: Matrix
    real: Matrix
    synthetic: Matrix
    n_real: int
    n_synthetic: int


def docking_hist_data(real: np.ndarray, synthetic: np.ndarray, bins: int = 20) -> DockingHistograms:
    """Histogram densities of real and synthetic errors on shared edges (pure).

    Args:
        real: Measured errors (n, 3), mm, mm, deg.
        synthetic: Generated errors (m, 3), same units.
        bins: Bins per component; the edges span both samples.

    Raises:
        InputError: Bad shapes, non-finite values or ``bins < 1``.
    """
    r, s = _errors(real, "real"), _errors(synthetic, "synthetic")
    if bins < 1:
        raise InputError(f"histogram bins must be >= 1, got {bins}")
    edges, dr, ds = [], [], []
    for j in range(3):
        both = np.concatenate([r[:, j], s[:, j]])
        e = np.histogram_bin_edges(both, bins=bins)
        edges.append(e)
        dr.append(np.histogram(r[:, j], bins=e, density=True)[0])
        ds.append(np.histogram(s[:, j], bins=e, density=True)[0])
    return DockingHistograms(DOCKING_LABELS, _rows(edges), _rows(dr), _rows(ds), len(r), len(s))


def plot_docking_histograms(data: DockingHistograms, fig: Figure | None = None) -> Figure:
    """Draw Fig. 6.9/6.11a: one axes per component, real filled, synthetic outlined.

    Args:
        data: From `docking_hist_data`.
        fig: Empty figure to draw into; a new 12 × 3.6 in figure when ``None``.
    """
    fig = fig if fig is not None else new_figure(12.0, 3.6)
    axes = fig.subplots(1, 3)
    for j, ax in enumerate(axes):
        ax.stairs(data.real[j], data.edges[j], fill=True, alpha=0.45, color=_REAL,
                  label=f"real (n = {data.n_real})")  # fmt: skip
        ax.stairs(data.synthetic[j], data.edges[j], linewidth=1.8, color=_SYNTH,
                  label=f"synthetic (n = {data.n_synthetic})")  # fmt: skip
        ax.set_xlabel(data.labels[j])
        ax.set_ylabel("density")
    fig.legend(*axes[0].get_legend_handles_labels(), loc="outside lower center", ncol=2)
    fig.suptitle("docking errors: real vs synthetic")
    return fig


@dataclass(frozen=True)
class DockingCorrelations:
    """Plot data of Fig. 6.10/6.11b: 3×3 Pearson correlations of both samples."""

    labels: tuple[str, ...]
    real: Matrix
    synthetic: Matrix


def docking_correlation_data(real: np.ndarray, synthetic: np.ndarray) -> DockingCorrelations:
    """Pearson correlation matrices of the real and the synthetic errors (pure).

    Raises:
        InputError: Bad shapes, non-finite values or a constant component.
    """
    r, s = _errors(real, "real"), _errors(synthetic, "synthetic")
    if np.any(np.ptp(r, axis=0) == 0) or np.any(np.ptp(s, axis=0) == 0):
        raise InputError("docking errors: a constant component has no correlation")
    cr, cs = np.corrcoef(r, rowvar=False), np.corrcoef(s, rowvar=False)
    return DockingCorrelations(DOCKING_LABELS, _rows(cr), _rows(cs))


def plot_correlation_matrices(data: DockingCorrelations, fig: Figure | None = None) -> Figure:
    """Draw Fig. 6.10/6.11b: two annotated heatmaps (real, synthetic) on one colour scale.

    Args:
        data: From `docking_correlation_data`.
        fig: Empty figure to draw into; a new 10 × 4.4 in figure when ``None``.
    """
    fig = fig if fig is not None else new_figure(10.0, 4.4)
    axes = fig.subplots(1, 2)
    ticks = [lab.split(" ")[0] for lab in data.labels]
    image = None
    for ax, title, mat in zip(
        axes, ("real", "synthetic"), (data.real, data.synthetic), strict=True
    ):
        m = np.asarray(mat)
        image = ax.imshow(m, vmin=-1.0, vmax=1.0, cmap="RdBu_r")
        ax.set_xticks(range(3), labels=ticks)
        ax.set_yticks(range(3), labels=ticks)
        for (i, k), v in np.ndenumerate(m):
            ax.text(k, i, f"{v:.2f}", ha="center", va="center",
                    color="white" if abs(v) > 0.6 else "black")  # fmt: skip
        ax.set_title(title)
    fig.colorbar(image, ax=list(axes), shrink=0.85, label="Pearson correlation")
    return fig
