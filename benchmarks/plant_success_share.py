"""Success share of emulated plants beside the real data's, in one run.

The plant's hidden-feature prior (`transfertwin.plant._truth`) is meant to give plants
that succeed about as often as the real cores do. For each plant seed this runs the
rehearsal's calibration design (`calibration_design`: K random pre-transfer states, the
objects in turn) on a fresh `EmulatedPlant` and prints its success share with a
Clopper–Pearson 95 % interval, beside the share of the 191 real calibration experiments
(the baseline) and their ratio.

    PYTHONPATH=src .venv/bin/python benchmarks/plant_success_share.py \
        [--seeds 1,2,3,4,5,6] [-k 148] [--objects o1,...,o37] [--workers 2]
"""

from __future__ import annotations

import argparse
import time

from statsmodels.stats.proportion import proportion_confint

from transfertwin.data import calibration_csv_path
from transfertwin.plant import EmulatedPlant
from transfertwin.rehearsal import calibration_design
from transfertwin.store import read_results


def _share(k: int, n: int) -> str:
    low, high = proportion_confint(k, n, method="beta")
    return f"{k}/{n} = {k / n:.3f} [{low:.2f}, {high:.2f}]"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", default="1,2,3,4,5,6")
    ap.add_argument("-k", type=int, default=148, help="experiments per plant")
    ap.add_argument("--objects", default=",".join(f"o{i}" for i in range(1, 38)))
    ap.add_argument("--workers", type=int, default=2)
    args = ap.parse_args()
    objects = [o.strip() for o in args.objects.split(",") if o.strip()]

    real = [int(r["success"]) for r in read_results(calibration_csv_path())]
    base = sum(real) / len(real)
    print(f"real calibration experiments: {_share(sum(real), len(real))}")
    shares = []
    for seed in (int(s) for s in args.seeds.split(",")):
        t0 = time.perf_counter()
        rows = EmulatedPlant(seed).run(
            calibration_design(objects, args.k, seed), workers=args.workers
        )
        ok = sum(int(r["success"]) for r in rows)
        shares.append(ok / len(rows))
        print(f"plant seed {seed}: {_share(ok, len(rows))}, / real {ok / len(rows) / base:.2f}"
              f" ({time.perf_counter() - t0:.0f} s)")  # fmt: skip
    mean = sum(shares) / len(shares)
    print(f"mean over {len(shares)} plants: {mean:.3f}, / real {mean / base:.2f}")


if __name__ == "__main__":
    main()
