"""How close the detector's AABB comes to the ground truth over the study's states.

For each core, face, conveyor position (Eq. 6.3) and yaw on a coarse grid the object is
placed and settled, the camera is servoed onto it (Eq. 5.14) and one frame is run through
the detector (Fig. 5.14). Printed: the share of states with exactly one box, and the
largest face error of that box against the true AABB from the hulls (median, 95th
percentile, share within 1 cm and 2 cm), with clean and with noisy clouds. Baseline: the
same statistics of a plain box (no hidden undersides), which isolates the pipeline's own
error from what the camera cannot see.

    PYTHONPATH=src python benchmarks/perception_accuracy.py [--size 160x120] [--step 60]
"""

from __future__ import annotations

import argparse
import math
import time

import numpy as np

from transfertwin.ots import POSITIONS
from transfertwin.perception import (
    CameraIntrinsics,
    DepthCamera,
    DepthNoise,
    DetectorConfig,
    Workspace,
    ground_truth_aabb,
    look,
)
from transfertwin.sim import DockingError, SceneConfig, VirtualTransferSystem
from transfertwin.study import system_for


def _box_system(scene: SceneConfig) -> VirtualTransferSystem:
    h = np.array([0.2, 0.09, 0.08]) / 2
    verts = np.array([[sx * h[0], sy * h[1], sz * h[2]] for sx in (-1, 1) for sy in (-1, 1)
                      for sz in (-1, 1)])  # fmt: skip
    return VirtualTransferSystem((verts,), 1.0, np.zeros(3), np.eye(3) * 1e-3, scene)


def measure(system, scene, size, noise, step_deg, cfg) -> dict[str, float]:
    errors, single = [], 0
    ws = Workspace.for_layout(scene.layout, scene.gap_m)
    n = 0
    with DepthCamera(system.model, system.data, intrinsics=size, noise=noise) as cam:
        for face in ("front", "back"):
            for x, y in POSITIONS.values():
                for theta in range(-180 + step_deg, 181, step_deg):
                    system.reset(DockingError())
                    system.place(face, math.radians(theta), x, y)
                    system.clock.wait(0.3)
                    truth = ground_truth_aabb(system)
                    seen = look(cam, ws, truth, cfg=cfg, seed=n)
                    n += 1
                    boxes = seen.detection.boxes
                    single += len(boxes) == 1
                    best = seen.nearest(truth)
                    errors.append(best.corner_error(truth) if best else math.inf)
    e = np.array(errors)
    return {"n": n, "one_box": single / n, "median_mm": 1000 * float(np.median(e)),
            "p95_mm": 1000 * float(np.percentile(e, 95)), "within_1cm": float((e < 0.01).mean()),
            "within_2cm": float((e < 0.02).mean())}  # fmt: skip


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--size", default="160x120")
    ap.add_argument("--step", type=int, default=60, help="yaw grid step in degrees")
    ap.add_argument("--objects", default="o1,o18,o23,o32")
    ap.add_argument("--eps", type=float, default=None, help="DBSCAN eps (m)")
    args = ap.parse_args()
    w, h = (int(v) for v in args.size.split("x"))
    size = CameraIntrinsics(w, h)
    scene = SceneConfig()
    cfg = DetectorConfig() if args.eps is None else DetectorConfig(cluster_eps_m=args.eps)
    systems = {"box": _box_system(scene)}
    systems.update({oid: system_for(oid, "m", scene) for oid in args.objects.split(",")})
    print(f"frames {w}x{h}, yaw step {args.step} deg, DBSCAN eps {cfg.cluster_eps_m} m")
    for label, noise in (("clean", DepthNoise.clean()), ("noisy", DepthNoise())):
        for oid, system in systems.items():
            t0 = time.perf_counter()
            r = measure(system, scene, size, noise, args.step, cfg)
            dt = time.perf_counter() - t0
            print(f"{label:5s} {oid:4s} n={r['n']:3d} one box {r['one_box']:.2f}  "
                  f"error median {r['median_mm']:5.1f} mm  p95 {r['p95_mm']:5.1f} mm  "
                  f"<1 cm {r['within_1cm']:.2f}  <2 cm {r['within_2cm']:.2f}  "
                  f"({dt / r['n'] * 1000:.0f} ms/state)")  # fmt: skip


if __name__ == "__main__":
    main()
