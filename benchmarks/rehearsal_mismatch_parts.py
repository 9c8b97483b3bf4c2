"""Which structural mismatch changes the plant's outcomes: the mismatch plant with each part
switched off in turn, against the in-class plant of the same seed (issue 29).

All plants run the same requests — the rehearsal's random calibration design — with the same
per-experiment draws (station, docking error, placement seeds, outcome flip: they follow
from the plant seed and the experiment id), so outcome differences are the structure's.
Prints per plant: success share with its Clopper–Pearson 95 % interval; the share of
experiments whose outcome differs from the in-class plant's and from the full mismatch
plant's, with an exact McNemar test (scipy's binomial test on the discordant pairs) of the
share's change. The baseline is the in-class plant (first line). The parts
(`MISMATCH_PARTS`): shape (knobs, dents), mass, belts (ripple, skew), contact (solver and
contact model), appendage (a loose strip on hinges), compliant (a part on a ball joint),
sag (sagging decks on springs).

    python benchmarks/rehearsal_mismatch_parts.py [--plant-seed 1] [--objects o3,o7] [-n 40]
        [--workers 2]
"""

from __future__ import annotations

import argparse
import time

import numpy as np
from scipy.stats import binomtest

from transfertwin.plant import EmulatedPlant
from transfertwin.plant._mismatch import MISMATCH_PARTS
from transfertwin.rehearsal import calibration_design, parse_object_list


def _mcnemar(a: np.ndarray, b: np.ndarray) -> float:
    """Exact McNemar p-value of paired 0/1 outcomes (1.0 without discordant pairs)."""
    up, down = int(np.sum((a == 1) & (b == 0))), int(np.sum((a == 0) & (b == 1)))
    return 1.0 if up + down == 0 else float(binomtest(up, up + down, 0.5).pvalue)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--plant-seed", type=int, default=1)
    ap.add_argument("--objects", default="o3,o7")
    ap.add_argument("-n", "--experiments", type=int, default=40)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--workers", type=int, default=2)
    args = ap.parse_args()
    design = calibration_design(parse_object_list(args.objects), args.experiments, args.seed)
    plants = {"in-class": EmulatedPlant(args.plant_seed),
              "mismatch": EmulatedPlant(args.plant_seed, kind="mismatch")}  # fmt: skip
    for part in MISMATCH_PARTS:
        plants[f"mismatch without {part}"] = EmulatedPlant(
            args.plant_seed, kind="mismatch", mismatch_off=(part,)
        )
    outcomes, t0 = {}, time.perf_counter()
    for name, plant in plants.items():
        rows = plant.run(design, workers=args.workers)
        outcomes[name] = np.array([int(r["success"]) for r in rows])
    base, full = outcomes["in-class"], outcomes["mismatch"]
    print(f"plant seed {args.plant_seed}, {args.objects}, {len(design)} experiments per plant "
          f"(same states and draws), {time.perf_counter() - t0:.0f} s on {args.workers} workers")
    for name, y in outcomes.items():
        ci = binomtest(int(y.sum()), len(y)).proportion_ci(method="exact")
        print(f"{name:28s} success {y.mean():.3f} [{ci.low:.2f}, {ci.high:.2f}]  "
              f"differs from in-class {np.mean(y != base):.3f} (McNemar p "
              f"{_mcnemar(y, base):.3f}), from the full mismatch {np.mean(y != full):.3f}")


if __name__ == "__main__":
    main()
