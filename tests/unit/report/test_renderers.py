"""Renderers draw into pyplot-free figures with the expected axes and save as PNG."""

from __future__ import annotations

from pathlib import Path

from matplotlib.figure import Figure

from transfertwin.report import (
    binary_polar_data,
    figure_png,
    interval_plot_data,
    plot_binary_polar,
    plot_intervals,
    plot_polar_full_state,
    polar_full_state_data,
)
from transfertwin.study.fullstate import select, series_table, state_table

PNG_MAGIC = b"\x89PNG\r\n\x1a\n"


def rows() -> list[dict]:
    out = []
    for t in range(-179, 181, 7):
        for face in ("front", "back"):
            conv = "left" if abs(t) <= 25 or abs(t) >= 155 else "both"
            ok = int((t // 7) % 3 != 0)
            out.append(dict(object_id="o1", face=face, conveyor=conv, theta_deg=t, success=ok))
    return out


def test_fig_6_20_plot_polar_full_state(tmp_path: Path) -> None:
    stats = state_table(rows())
    fig = plot_polar_full_state(
        polar_full_state_data(series_table(stats, "o1"), select(stats, "o1"))
    )
    assert isinstance(fig, Figure)
    assert [ax.name for ax in fig.axes] == ["polar", "polar"]
    fig.savefig(tmp_path / "polar.png")
    assert (tmp_path / "polar.png").read_bytes().startswith(PNG_MAGIC)


def test_fig_6_7_plot_binary_polar_into_given_figure() -> None:
    fig = Figure()
    out = plot_binary_polar(binary_polar_data(rows(), "o1"), fig=fig)
    assert out is fig
    assert [ax.name for ax in fig.axes].count("polar") == 2  # and the share's colour bar
    assert figure_png(fig).startswith(PNG_MAGIC)


def test_fig_6_22_plot_intervals(tmp_path: Path) -> None:
    stats = state_table(rows())
    fig = plot_intervals(interval_plot_data([select(stats, "o1")], "best"))
    assert len(fig.axes) == 1
    fig.savefig(tmp_path / "ci.png")
    assert (tmp_path / "ci.png").stat().st_size > 0
    ax = Figure().add_subplot(1, 1, 1)
    assert (
        plot_intervals(interval_plot_data([select(stats, "o1")], "worst"), ax=ax) is ax.get_figure()
    )


def _texts(ax) -> set[str]:
    return {t.get_text() for t in ax.texts}


def test_binary_polar_labels_each_ring_with_its_conveyor() -> None:
    fig = plot_binary_polar(binary_polar_data(rows(), "o1"))
    for ax in (a for a in fig.axes if a.name == "polar"):
        assert {"c = left", "c = both", "c = right"} <= _texts(ax)
    legend = [t.get_text() for t in fig.legends[0].get_texts()]
    assert "outer ring: conveyor c = left" in legend and "inner ring: conveyor c = right" in legend


def test_full_state_plot_says_what_the_radius_is_and_keeps_labels_off_the_rim() -> None:
    stats = state_table(rows())
    fig = plot_polar_full_state(
        polar_full_state_data(series_table(stats, "o1"), select(stats, "o1"))
    )
    for ax in fig.axes:
        assert any(t.startswith("radius = success rate") for t in _texts(ax))
        # Radius tick labels sit off the 0° spoke, and none on the rim where curves run.
        assert ax.get_rlabel_position() != 0.0
        assert [t.get_text() for t in ax.get_yticklabels()][-1] == ""


def test_binary_polar_draws_one_marker_per_state_coloured_by_its_share() -> None:
    """Issue 30.1: 6 of 8 successes at one state is one marker at share 0.75, not a red dot
    drawn over green ones."""
    import numpy as np

    runs = [dict(object_id="o32", face="front", conveyor="both", theta_deg=-60,
                 success=int(r < 6)) for r in range(8)]  # fmt: skip
    data = binary_polar_data(runs, "o32")
    fig = plot_binary_polar(data)
    front = fig.axes[0]
    offsets = np.concatenate([c.get_offsets() for c in front.collections if len(c.get_offsets())])
    assert len(offsets) == 1  # one state, one marker
    (coll,) = [c for c in front.collections if len(c.get_offsets())]
    rgba = coll.to_rgba(coll.get_array())[0]
    assert np.allclose(rgba, coll.cmap(coll.norm(0.75)))
    assert "6/8" in _texts(front)  # few states: each is labelled with its k/n
