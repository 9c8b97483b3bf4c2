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
from transfertwin.study.fullstate import select, state_table

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
    fig = plot_polar_full_state(polar_full_state_data(stats, select(stats, "o1")))
    assert isinstance(fig, Figure)
    assert [ax.name for ax in fig.axes] == ["polar"] * 6  # face x conveyor
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
    fig = plot_polar_full_state(polar_full_state_data(stats, select(stats, "o1")))
    assert "radius = success share (centre 0, rim 1)" in fig.get_suptitle()
    for ax in fig.axes:
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


def _step30_rows() -> list[dict]:
    """Both faces at θ-step 30, 8 runs a state; front fails everywhere at θ = -150 only."""
    out = []
    for face in ("front", "back"):
        for t in range(-150, 181, 30):
            convs = ("left", "right") if t in (0, 180) else ("both",)
            for conv in convs:
                wins = 0 if (face, t) == ("front", -150) else 8
                out += [dict(object_id="o1", face=face, conveyor=conv, theta_deg=t,
                             success=int(r < wins)) for r in range(8)]  # fmt: skip
    return out


def test_full_state_plot_has_one_panel_per_conveyor_value_with_its_own_states() -> None:
    """One panel per face and conveyor value (left, both, right): a left panel holds the
    left states only (never the 'both' ones as well), each state a dot with its interval
    bar; 8 runs a state 30° apart support no smoothed line."""
    import math

    stats = state_table(_step30_rows())
    fig = plot_polar_full_state(polar_full_state_data(stats, select(stats, "o1")))
    polar = [ax for ax in fig.axes if ax.name == "polar"]
    titles = [ax.get_title().splitlines() for ax in polar]
    assert [t[0] for t in titles] == [
        "front face, on the left belt",
        "front face, centred across both belts",
        "front face, on the right belt",
        "back face, on the left belt",
        "back face, centred across both belts",
        "back face, on the right belt",
    ]
    assert titles[0][1].startswith("16 runs at 2 angles")  # θ = 0 and 180, 8 runs each
    assert titles[1][1].startswith("80 runs at 10 angles")
    left = polar[0]
    dots = [c for c in left.collections if len(c.get_offsets())]
    thetas = sorted(round(math.degrees(t)) % 360 for t in dots[0].get_offsets()[:, 0])
    assert thetas == [0, 180]
    bars = [ln for ln in left.lines if len(ln.get_xdata()) == 2
            and ln.get_xdata()[0] == ln.get_xdata()[1] and max(ln.get_ydata()) < 1.05]  # fmt: skip
    assert len(bars) == 2  # one interval bar per state
    for ax in polar:
        assert not any(len(line.get_xdata()) == 361 for line in ax.lines)


def test_full_state_plot_marks_the_angle_of_a_worst_state_at_radius_0() -> None:
    """The worst state (0 of 8, drawn at the centre) keeps its angle: a radial line from
    the centre to the rim at its θ and a label with θ in degrees."""
    import math

    import numpy as np

    stats = state_table(_step30_rows())
    sel = select(stats, "o1")
    assert (sel.worst.theta_deg, sel.worst.conveyor, sel.worst.p_hat) == (-150, "both", 0.0)
    fig = plot_polar_full_state(polar_full_state_data(stats, sel))
    panel = fig.axes[1]  # front, both: the worst state's own conveyor
    spokes = [
        line for line in panel.lines
        if len(set(line.get_xdata())) == 1 and line.get_xdata()[0] == math.radians(-150)
        and max(line.get_ydata()) >= 1.05
    ]  # fmt: skip
    assert spokes and min(spokes[0].get_ydata()) == 0.0
    labels = dict(zip(np.degrees(panel.get_xticks()).round(6) % 360,
                      (t.get_text() for t in panel.get_xticklabels()), strict=True))  # fmt: skip
    assert labels[210.0] == "worst: θ = -150°"  # the tick label at its angle says so
    assert "-150°" not in labels.values() and labels[240.0] == "-120°"  # grid gives way


def test_issue_30_4_polar_axes_label_theta_signed_every_30_degrees() -> None:
    """θ runs over -179..180 (DESIGN), as in the tables: ticks every 30°, signed, so a
    state at θ = -150° is read off the plot under the label '-150°'."""
    from transfertwin.report import yaw_tick_labels

    signed = ["0°", "30°", "60°", "90°", "120°", "150°", "180°",
              "-150°", "-120°", "-90°", "-60°", "-30°"]  # fmt: skip
    assert yaw_tick_labels() == signed
    stats = state_table(_step30_rows())
    figs = (
        plot_polar_full_state(polar_full_state_data(stats, select(stats, "o1"))),
        plot_binary_polar(binary_polar_data(_step30_rows(), "o1")),
    )
    for fig in figs:
        for ax in (a for a in fig.axes if a.name == "polar"):
            labels = [t.get_text() for t in ax.get_xticklabels()]
            if not any(":" in lab for lab in labels):  # no best/worst state in this panel
                assert labels == signed
            for lab in labels:
                assert -179 <= int(lab.rsplit(" ", 1)[-1].rstrip("°")) <= 180
