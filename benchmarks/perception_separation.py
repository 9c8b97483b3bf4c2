"""Minimum separation at which two objects are still told apart, by camera angle (Fig. 5.17).

Two copies of a core lie one behind the other on the TM belts (`pair_scene`), crosswise
(θ = 90°), with a clear gap g between their AABBs; the camera looks at the pair from servo
angle α. For each α the smallest g on the grid from which on the detector reports two boxes
matching the two objects is printed, and drawn to a PNG. Baseline: the detector's DBSCAN
radius (eps), the separation an ideal, fully visible pair would need.

    PYTHONPATH=src python benchmarks/perception_separation.py [--object o1] [--out sep.png]
"""

from __future__ import annotations

import argparse
import math
import time

import numpy as np

from transfertwin.objects import load_object
from transfertwin.perception import (
    CameraIntrinsics,
    DepthCamera,
    DepthNoise,
    DetectorConfig,
    Workspace,
    min_separation,
    pair_scene,
)
from transfertwin.sim import SceneConfig


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--object", default="box", help="box (default) or a core id")
    ap.add_argument("--angles", default="-40,-30,-20,-10,0,10")
    ap.add_argument("--size", default="160x120")
    ap.add_argument("--out", default="", help="PNG of min separation vs angle")
    args = ap.parse_args()
    w, h = (int(v) for v in args.size.split("x"))
    scene_cfg = SceneConfig()
    if args.object == "box":  # 200 x 90 x 80 mm, nothing hidden under overhangs
        half = np.array([0.2, 0.09, 0.08]) / 2
        hulls = (np.array([[a * half[0], b * half[1], c * half[2]] for a in (-1, 1) for b in (-1, 1)
                           for c in (-1, 1)]),)  # fmt: skip
    else:
        hulls = load_object(args.object).hulls
    scene = pair_scene(hulls, scene_cfg)
    ws = Workspace.for_layout(scene_cfg.layout, scene_cfg.gap_m)
    cfg = DetectorConfig()
    gaps = np.round(np.arange(0.0, 0.0801, 0.005), 4)
    angles = [float(a) for a in args.angles.split(",")]
    results = []
    t0 = time.perf_counter()
    with DepthCamera(scene.model, scene.data, intrinsics=CameraIntrinsics(w, h),
                     noise=DepthNoise()) as cam:  # fmt: skip
        for a in angles:
            r = min_separation(scene, cam, ws, a, gaps, cfg=cfg)
            results.append(r)
            shown = "never" if math.isnan(r.min_gap_m) else f"{1000 * r.min_gap_m:.0f} mm"
            apart = "".join("2" if v else "1" for v in r.apart)
            print(f"alpha {a:6.1f} deg  pair at x = {r.centre_x_m:+.3f} m  min gap {shown:>6s}"
                  f"  (boxes per gap 0..80 mm: {apart})")  # fmt: skip
    print(
        f"baseline: DBSCAN eps = {1000 * cfg.cluster_eps_m:.0f} mm; "
        f"{time.perf_counter() - t0:.1f} s for {len(angles) * len(gaps)} frames"
    )
    if args.out:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt

        fig, ax = plt.subplots(figsize=(5, 3.5))
        ax.plot(angles, [1000 * r.min_gap_m for r in results], "o-", label=args.object)
        ax.axhline(1000 * cfg.cluster_eps_m, ls="--", c="0.5", label="DBSCAN eps")
        ax.set_xlabel("servo angle α (deg)")
        ax.set_ylabel("min. separation told apart (mm)")
        ax.legend()
        ax.grid(alpha=0.3)
        fig.tight_layout()
        fig.savefig(args.out, dpi=110)


if __name__ == "__main__":
    main()
