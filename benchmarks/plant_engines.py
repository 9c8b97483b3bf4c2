"""The same plant in two physics engines: MuJoCo (kind 'in-class') and PyBullet ('bullet').

Both plants of a seed hold the same hidden objects and scene and draw, per experiment id,
the same station, docking error, placement seeds and outcome flip; only the engine that
simulates the transfer differs (`transfertwin.plant._bullet`). This runs the rehearsal's
calibration design (`calibration_design`: K random pre-transfer states, the objects in
turn, a fixed seed) on a fresh plant of each kind, one process each, and prints

- each engine's success share with a Clopper–Pearson 95 % interval (per object too),
- their agreement row by row and McNemar's exact test of the discordant pairs,
- each engine's experiments per second and the ratio (the baseline: MuJoCo, in the same
  run, same machine),
- how each engine's simulations ended (benchmark only: it counts the statuses of the
  plant's private simulation loop, `transfertwin.plant._plant.run_experiment`; 'unstable'
  runs are run again at finer steps and 'invalid' ones placed again, as the plant does).

    PYTHONPATH=src .venv/bin/python benchmarks/plant_engines.py \
        [--plant-seed 1] [--objects o1,o3,o7,o12,o20,o29] [-k 120] [--seed 0]

(docs/fidelity.md, "The same plant in a second engine": seeds 1 and 2 with the defaults.)
"""

from __future__ import annotations

import argparse
import collections
import platform
import time

from statsmodels.stats.contingency_tables import mcnemar
from statsmodels.stats.proportion import proportion_confint

import transfertwin.plant._plant as plant_loop  # the statuses of the plant's simulations
from transfertwin.plant import EmulatedPlant
from transfertwin.rehearsal import calibration_design


def _share(k: int, n: int) -> str:
    low, high = proportion_confint(k, n, method="beta")
    return f"{k}/{n} = {k / n:.3f} [{low:.2f}, {high:.2f}]"


def _counting(statuses: collections.Counter):
    """`run_experiment` that counts its results' statuses."""
    run = plant_loop.run_experiment

    def counted(spec, **kwargs):
        result = run(spec, **kwargs)
        statuses[result.status] += 1
        return result

    return counted


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--plant-seed", type=int, default=1)
    ap.add_argument("--objects", default="o1,o3,o7,o12,o20,o29")
    ap.add_argument("-k", type=int, default=120, help="experiments per plant")
    ap.add_argument("--seed", type=int, default=0, help="seed of the design (the states)")
    args = ap.parse_args()
    objects = [o.strip() for o in args.objects.split(",") if o.strip()]
    design = calibration_design(objects, args.k, args.seed)
    print(f"plant seed {args.plant_seed}, {len(design)} experiments on {', '.join(objects)} "
          f"(design seed {args.seed}), one process each, {platform.machine()}")  # fmt: skip

    rows, rate, statuses = {}, {}, {}
    original = plant_loop.run_experiment
    for kind, engine in (("in-class", "MuJoCo"), ("bullet", "PyBullet")):
        statuses[engine] = collections.Counter()
        plant_loop.run_experiment = _counting(statuses[engine])
        t0 = time.perf_counter()
        try:
            rows[engine] = EmulatedPlant(args.plant_seed, kind=kind).run(design)
        finally:
            plant_loop.run_experiment = original
        wall = time.perf_counter() - t0
        rate[engine] = len(design) / wall
        ok = sum(int(r["success"]) for r in rows[engine])
        print(f"{engine:9s} (kind {kind!r}): success {_share(ok, len(design))}, "
              f"{wall:.1f} s, {rate[engine]:.2f} experiments/s")  # fmt: skip
    mj, pb = ([int(r["success"]) for r in rows[e]] for e in ("MuJoCo", "PyBullet"))
    assert [r["dock_err_x_mm"] for r in rows["MuJoCo"]] == [
        r["dock_err_x_mm"] for r in rows["PyBullet"]
    ]  # the same draws
    print(f"{'object':8s} {'MuJoCo':>24s} {'PyBullet':>24s} {'agree':>6s}")
    for obj in objects:
        idx = [i for i, r in enumerate(rows["MuJoCo"]) if r["object_id"] == obj]
        a, b = sum(mj[i] for i in idx), sum(pb[i] for i in idx)
        agree = sum(mj[i] == pb[i] for i in idx) / len(idx)
        print(f"{obj:8s} {_share(a, len(idx)):>24s} {_share(b, len(idx)):>24s} {agree:6.2f}")
    both = sum(a and b for a, b in zip(mj, pb, strict=True))
    only_mj = sum(a and not b for a, b in zip(mj, pb, strict=True))
    only_pb = sum(b and not a for a, b in zip(mj, pb, strict=True))
    neither = len(mj) - both - only_mj - only_pb
    agree = (both + neither) / len(mj)
    test = mcnemar([[both, only_mj], [only_pb, neither]], exact=True)
    print(f"agreement {both + neither}/{len(mj)} = {agree:.3f}; discordant: MuJoCo only "
          f"{only_mj}, PyBullet only {only_pb}; McNemar exact p = {test.pvalue:.3f}")  # fmt: skip
    for engine, counts in statuses.items():
        print(f"{engine} simulations (with re-runs): "
              + ", ".join(f"{k} {v}" for k, v in sorted(counts.items())))  # fmt: skip
    print(f"speed: PyBullet {rate['PyBullet']:.2f} / MuJoCo {rate['MuJoCo']:.2f} experiments/s "
          f"= {rate['PyBullet'] / rate['MuJoCo']:.2f}x")  # fmt: skip


if __name__ == "__main__":
    main()
