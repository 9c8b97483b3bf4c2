"""Drawing what the camera saw: the cloud, its clusters, the boxes and the truth.

Data first: everything drawn comes from a `Detection`, the frames' poses and the true AABB;
this module only draws (matplotlib, Agg) and saves.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import numpy as np

from transfertwin.perception._aabb import AABB
from transfertwin.perception._camera import View
from transfertwin.perception._detector import Detection

__all__ = ["plot_detection"]


def _rect(ax, box: AABB, dims: tuple[int, int], **style) -> None:
    from matplotlib.patches import Rectangle

    lo, hi = box.lo, box.hi
    i, j = dims
    ax.add_patch(Rectangle((lo[i], lo[j]), hi[i] - lo[i], hi[j] - lo[j], fill=False, **style))


def plot_detection(
    detection: Detection,
    views: Sequence[View],
    path: str | Path,
    *,
    truth: AABB | None = None,
    title: str = "",
) -> Path:
    """Top view (x, y) and side view (x, z) in F_T of the clustered cloud, one colour per
    cluster (grey: not an object), detected AABBs (solid) and the true AABB (dashed), and
    the camera's position and optical axis per frame. Writes a PNG."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    path = Path(path)
    fig, (top, side) = plt.subplots(2, 1, figsize=(9, 7.5), height_ratios=(1.2, 1))
    pts, labels = detection.points, detection.labels
    colours = plt.get_cmap("tab10")
    for ax, (i, j) in ((top, (0, 1)), (side, (0, 2))):
        noise = labels < 0
        ax.scatter(pts[noise, i], pts[noise, j], s=1, c="0.75", label="not an object")
        for k, box in enumerate(detection.boxes):
            members = labels == k
            c = colours(k % 10)
            ax.scatter(pts[members, i], pts[members, j], s=2, color=c,
                       label=f"cluster {k + 1} ({box.n_points} pts)")  # fmt: skip
            _rect(ax, box, (i, j), edgecolor=c, linewidth=1.5)
        if truth is not None:
            _rect(ax, truth, (i, j), edgecolor="k", linestyle="--", linewidth=1.2)
            ax.plot([], [], "k--", label="true AABB (hulls)")
        ax.set_aspect("equal")
        ax.grid(alpha=0.3)
        ax.set_xlabel("x in F_T (m)")
    top.set_ylabel("y in F_T (m)")
    side.set_ylabel("z in F_T (m)")
    for v in views:
        o, axis = v.t_tc[:3, 3], v.t_tc[:3, 2]
        end = o + axis * (o[2] / max(-axis[2], 1e-6))
        side.plot([o[0], end[0]], [o[2], end[2]], ":", color="tab:red")
        side.plot(o[0], o[2], "v", color="tab:red")
        side.annotate(f"α = {np.degrees(v.alpha_rad):.0f}°", (o[0], o[2]), fontsize=8,
                      xytext=(4, 4), textcoords="offset points")  # fmt: skip
    top.legend(loc="upper left", fontsize=7, markerscale=4, ncol=2)
    fig.suptitle(title, fontsize=10)
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(path.name + ".tmp")
    fig.savefig(tmp, format="png", dpi=110)
    plt.close(fig)
    tmp.replace(path)
    return path
