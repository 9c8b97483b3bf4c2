"""Plot data and renderers of real vs synthetic docking errors (Fig. 6.9–6.11)."""

from __future__ import annotations

import numpy as np
import pytest
from matplotlib.figure import Figure

from transfertwin._errors import InputError
from transfertwin.report._docking_plots import (
    docking_correlation_data,
    docking_hist_data,
    plot_correlation_matrices,
    plot_docking_histograms,
)
from transfertwin.report._figure import figure_png

PNG_MAGIC = b"\x89PNG\r\n\x1a\n"


def _pair() -> tuple[np.ndarray, np.ndarray]:
    rng = np.random.default_rng(0)
    cov = [[4.0, -3.0, 0.1], [-3.0, 9.0, 0.5], [0.1, 0.5, 0.4]]
    return rng.multivariate_normal([0, 0, 1], cov, 191), rng.multivariate_normal(
        [0, 0, 1], cov, 900
    )


def test_fig_6_9_histograms_are_densities_on_shared_edges() -> None:
    real, synth = _pair()
    data = docking_hist_data(real, synth, bins=15)
    assert (data.n_real, data.n_synthetic) == (191, 900)
    for j in range(3):
        edges = np.asarray(data.edges[j])
        assert len(edges) == 16
        assert edges[0] == min(real[:, j].min(), synth[:, j].min())
        assert edges[-1] == max(real[:, j].max(), synth[:, j].max())
        for dens in (data.real[j], data.synthetic[j]):
            assert np.sum(np.asarray(dens) * np.diff(edges)) == pytest.approx(1.0)


def test_fig_6_10_correlations_are_pearson_of_each_sample() -> None:
    real, synth = _pair()
    data = docking_correlation_data(real, synth)
    np.testing.assert_allclose(data.real, np.corrcoef(real.T))
    np.testing.assert_allclose(data.synthetic, np.corrcoef(synth.T))
    assert data.labels == ("e_x [mm]", "e_y [mm]", "e_θ [deg]")


def test_fig_6_9_and_6_10_renderers_draw_pyplot_free_figures() -> None:
    real, synth = _pair()
    hist = plot_docking_histograms(docking_hist_data(real, synth))
    corr = plot_correlation_matrices(docking_correlation_data(real, synth))
    assert isinstance(hist, Figure) and len(hist.axes) == 3
    assert isinstance(corr, Figure) and len(corr.axes) == 3  # two heatmaps and a colour bar
    texts = [t.get_text() for t in corr.axes[0].texts]
    assert len(texts) == 9 and texts[0] == "1.00"
    assert figure_png(hist).startswith(PNG_MAGIC) and figure_png(corr).startswith(PNG_MAGIC)


@pytest.mark.parametrize(
    ("real", "match"),
    [
        (np.zeros((5, 2)), r"expected an \(n >= 2, 3\) array"),
        (np.full((5, 3), np.nan), "finite"),
    ],
)
def test_fig_6_9_bad_arrays_are_input_error(real: np.ndarray, match: str) -> None:
    _, synth = _pair()
    with pytest.raises(InputError, match=match):
        docking_hist_data(real, synth)
    with pytest.raises(InputError, match=match):
        docking_correlation_data(real, synth)


def test_fig_6_10_constant_component_is_input_error() -> None:
    real, synth = _pair()
    real[:, 2] = 1.0
    with pytest.raises(InputError, match="constant component"):
        docking_correlation_data(real, synth)
    with pytest.raises(InputError, match="bins"):
        docking_hist_data(real, synth, bins=0)
