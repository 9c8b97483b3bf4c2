"""Draw how a mesh is put on the belt: ``docs/img/mesh-convention.png``.

Any mesh — a built-in core or a user's STL/OBJ/PLY file — is used *as modelled*: the file's
+x axis is the object's x axis, 'front' is the mesh lying as modelled (+z up, on its lowest
side), 'back' is it turned over by 180° about x, and at θ = 0 its +x points in the direction
of travel TM → TU, θ counter-clockwise positive seen from above (docs/design-choices.md,
"Object frame, faces and placement"). The picture shows this on the built-in core o1.

Usage (with the package installed, or ``PYTHONPATH=src``)::

    .venv/bin/python scripts/make_mesh_convention.py [--object o1] [--out FILE]
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np
from matplotlib.axes import Axes
from matplotlib.collections import PolyCollection
from matplotlib.patches import FancyArrowPatch, Rectangle

from transfertwin.objects import load_object
from transfertwin.report import figure_png
from transfertwin.report._figure import new_figure

DEFAULT_OUT = Path(__file__).resolve().parents[1] / "docs" / "img" / "mesh-convention.png"
_BODY = "#b8c4d6"
_NEAR = "#6f86a8"  # the half on the file's -y side (the solenoid of a built-in core)
_X_COLOR = "#d62728"
_BELT = "#444444"


def _silhouette(
    ax: Axes, vertices: np.ndarray, faces: np.ndarray, axes: tuple[int, int], file_y: np.ndarray
) -> None:
    """Fill the projection of every triangle onto two coordinate axes (mm); triangles on the
    file's -y side darker, drawn last."""
    tris = vertices[faces][:, :, list(axes)] * 1000.0
    near = file_y[faces].mean(axis=1) < 0.0
    for mask, color in ((~near, _BODY), (near, _NEAR)):
        ax.add_collection(PolyCollection(tris[mask], facecolor=color, edgecolor=color,
                                         linewidth=0.3))  # fmt: skip


def _arrow(ax: Axes, start, end, color: str, label: str, offset=(4, 4)) -> None:
    ax.add_patch(FancyArrowPatch(start, end, arrowstyle="-|>", mutation_scale=14, color=color,
                                 linewidth=2))  # fmt: skip
    ax.annotate(label, end, textcoords="offset points", xytext=offset, color=color,
                fontsize=10, fontweight="bold")  # fmt: skip


def _end(
    ax: Axes, vertices: np.ndarray, faces: np.ndarray, file_y: np.ndarray, title: str, flip: float
) -> None:
    """End view from +x (y right, z up) of the object resting on the belt at its lowest
    point, with the file's +y and +z axes (turned over when ``flip`` is -1)."""
    v = vertices - [0.0, 0.0, vertices[:, 2].min()]
    _silhouette(ax, v, faces, (1, 2), file_y)
    ax.add_patch(Rectangle((-120, -8), 240, 8, color=_BELT))
    ax.text(-115, -14, "belt", ha="left", va="top", fontsize=9)
    centre = (0.0, float(v[:, 2].max() + v[:, 2].min()) * 500.0)
    _arrow(ax, centre, (centre[0] + 60 * flip, centre[1]), "#9467bd", "+y")
    _arrow(ax, centre, (centre[0], centre[1] + 55 * flip), "#1f77b4", "+z", offset=(5, -4))
    ax.plot(*centre, marker="o", ms=9, mfc="white", mec=_X_COLOR, mew=2)
    ax.plot(*centre, marker=".", ms=5, color=_X_COLOR)
    ax.annotate("+x towards you", centre, textcoords="offset points", xytext=(-80, -16),
                color=_X_COLOR, fontsize=8)  # fmt: skip
    ax.set_title(title, fontsize=10)


def _top(ax: Axes, vertices: np.ndarray, faces: np.ndarray) -> None:
    """Top view on the two belts at θ = 0: +x in the direction of travel; θ positive CCW."""
    for y0, name in ((5.0, "left belt"), (-200.0, "right belt")):
        ax.add_patch(Rectangle((-200, y0), 400, 195, color="#e6e6e6"))
        top = y0 > 0
        ax.text(-195, y0 + (180 if top else 8), name, fontsize=8, va="top" if top else "bottom")
    _silhouette(ax, vertices, faces, (0, 1), vertices[:, 1])
    _arrow(ax, (-190, -215), (190, -215), _BELT, "direction of travel: TM → TU", offset=(-180, -14))
    _arrow(ax, (0, 0), (110, 0), _X_COLOR, "+x at θ = 0")
    arc = np.radians(np.linspace(0, 60, 30))
    ax.plot(140 * np.cos(arc), 140 * np.sin(arc), color="#2ca02c", lw=1.5)
    tip = [(140 * np.cos(a), 140 * np.sin(a)) for a in arc[-2:]]
    _arrow(ax, tip[0], tip[1], "#2ca02c", "+θ", offset=(-18, 4))
    ax.set_title("seen from above at θ = 0 (centred on 'both')", fontsize=10)


def draw(ref: str = "o1"):
    """The three-panel figure for object `ref` (built-in id or mesh path)."""
    obj = load_object(ref)
    v, f = np.asarray(obj.mesh.vertices), np.asarray(obj.mesh.faces)
    back = v * [1.0, -1.0, -1.0]  # turned over by 180° about x
    fig = new_figure(12.0, 4.0)
    axes = fig.subplots(1, 3, gridspec_kw={"width_ratios": [1.0, 1.0, 1.6]})
    _end(axes[0], v, f, v[:, 1], f"'front': {ref} as modelled, +z up\n(seen from +x)", 1.0)
    _end(axes[1], back, f, v[:, 1], "'back': turned over 180° about x\n(seen from +x)", -1.0)
    _top(axes[2], v, f)
    for ax in axes:
        ax.set_aspect("equal")
        ax.autoscale_view()
        ax.set_xticks([])
        ax.set_yticks([])
        for side in ax.spines.values():
            side.set_visible(False)
    for ax in axes[:2]:
        ax.set_xlim(-130, 130)
        ax.set_ylim(-35, 160)
    axes[2].set_xlim(-210, 210)
    axes[2].set_ylim(-240, 210)
    fig.suptitle("How a mesh is put on the belt: as modelled (any STL/OBJ/PLY or built-in "
                 "core); darker: the file's −y half", fontsize=11)  # fmt: skip
    return fig


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--object", default="o1", help="built-in core or mesh path (default o1)")
    p.add_argument("--out", type=Path, default=DEFAULT_OUT, help="PNG to write")
    args = p.parse_args(argv)
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_bytes(figure_png(draw(args.object), dpi=80))
    print(args.out)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
