"""Measure the spread of the unit camera's ChArUco docking-error measurement, the basis of
the sigmas PropS is told (`cps.roles.CAMERA_SIGMA_XY_M`, docs/architecture.md, "PropS in
the loop").

    python scripts/charuco_sigma.py [--n 30] [--seed 0] [--noise 3.0]

True docking errors are drawn with σ = 5 mm (x, y) and 0.01 rad (θ); each is rendered with
`CharucoRig` (Gaussian grey-level noise of `--noise`) and measured (Eq. 6.11). Prints the
mean and the standard deviation of measured minus true.
"""

from __future__ import annotations

import argparse

import numpy as np


def main() -> None:
    from transfertwin.navigation import CharucoRig

    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--n", type=int, default=30)
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--noise", type=float, default=3.0, help="grey levels (0-255), 1 sigma")
    args = p.parse_args()
    rig = CharucoRig(pixel_noise_sd=args.noise)
    rng = np.random.default_rng(args.seed)
    diffs, missed = [], 0
    for _ in range(args.n):
        xi = rng.normal(0.0, 1.0, 3) * [0.005, 0.005, 0.01]
        seen = rig.measure_error(xi, rng)
        if seen is None:
            missed += 1
            continue
        diffs.append(seen - xi)
    d = np.array(diffs)
    print(f"{len(d)} measured, {missed} without the board; measured - true:")
    print(f"  mean  x {d[:, 0].mean() * 1e3:+.4f} mm  y {d[:, 1].mean() * 1e3:+.4f} mm  "
          f"theta {d[:, 2].mean() * 1e3:+.4f} mrad")  # fmt: skip
    sd = d.std(axis=0, ddof=1)
    print(f"  sd    x {sd[0] * 1e3:.4f} mm  y {sd[1] * 1e3:.4f} mm  theta {sd[2] * 1e3:.4f} mrad")
    print("PropS is told 0.1 mm and 0.5 mrad (cps.roles.CAMERA_SIGMA_*)")


if __name__ == "__main__":
    main()
