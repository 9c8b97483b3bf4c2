"""ORACLE: which mismatch keeps a rehearsal's calibrated twin from its oracle (issue 29,
item 4) — reads the plant's hidden parameters.

**Benchmark only**, like `benchmarks/rehearsal_oracle.py`: it opens the emulated plant's
private experiment machinery (`EmulatedPlant._jobs`, `transfertwin.plant._plant._run_job`),
which no part of the twin or of `transfertwin rehearse` may do.

For a rehearsal folder on the mismatch plant (its plant seed read from ``plant.secret``
beside ``rehearsal.json``) it rebuilds the held-out experiments (the oracle's way: the
same states, logged docking errors and ids) and runs each again on variants of the same
plant, ``--n`` times with fresh placement seeds and no outcome flips: the full mismatch
plant, the mismatch plant with one part switched off
(`transfertwin.plant._mismatch.MISMATCH_PARTS`), and the in-class plant. Per variant it
prints the variant's success share on those rows and the calibrated twin's held-out
decisions (``p_after >= 0.5`` in ``held_out_predictions.csv``) scored against the variant's
majority outcome: F0.5 and agreement, with the difference from the full mismatch plant's.

Reading it: the twin was calibrated on the full mismatch plant and cannot represent its
structural parts. A part whose removal makes the plant agree markedly better with the
twin's decisions is one the twin's model class misses on these rows; a part whose removal
changes nothing is not what keeps it from the oracle. The parts interact (switching one off
moves outcomes near the edge both ways), so the differences are indications, not a sum.

    python benchmarks/rehearsal_mismatch_gap.py DIR [--n 2] [--workers 2]
"""

from __future__ import annotations

import argparse
import csv
import json
import time
from pathlib import Path

import numpy as np

from rehearsal_oracle import _f05, rerun_wins  # ORACLE: reruns the plant's private jobs
from transfertwin.plant import (
    MISMATCH_PARTS,
    PLANT_SEED_FILE,
    EmulatedPlant,
    read_plant_seed,
)
from transfertwin.rehearsal import calibration_design


def _shares(plant: EmulatedPlant, design, ids: list[tuple[int, tuple[str, int]]], seed: int,
            n: int, workers: int) -> np.ndarray:  # fmt: skip
    """Each held-out row's (id, (face, θ)) success share over `n` reruns on `plant` (no
    flips)."""
    by_id = {j.experiment_id: j for j in plant._jobs(design)}
    jobs = [by_id[eid] for eid, _ in ids]
    for j, (_, (face, theta)) in zip(jobs, ids, strict=True):  # the logged state
        assert (j.request.face, j.request.theta_deg) == (face, theta)
    return rerun_wins(jobs, 0x47415050, seed, n, workers).mean(axis=1)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("folder", type=Path, help="a rehearsal folder of a mismatch plant")
    ap.add_argument("--n", type=int, default=2, help="reruns per held-out row and variant")
    ap.add_argument("--workers", type=int, default=2)
    args = ap.parse_args()
    doc = json.loads((args.folder / "rehearsal.json").read_text())
    cfg = doc["config"]
    if cfg.get("plant_kind") != "mismatch":
        raise SystemExit(f"{args.folder}: not a rehearsal on the mismatch plant")
    if int(cfg.get("test_experiments", 0)):
        raise SystemExit(f"{args.folder}: separate test experiments are not supported here")
    rows = list(csv.DictReader((args.folder / "held_out_predictions.csv").open()))
    ids = [(int(r["experiment_id"]), (r["face"], int(r["theta_deg"]))) for r in rows]
    y = np.array([int(r["success"]) for r in rows])
    twin = np.array([float(r["p_after"]) >= 0.5 for r in rows])
    seed = read_plant_seed(args.folder / PLANT_SEED_FILE)  # not in rehearsal.json
    design = calibration_design(tuple(cfg["objects"]), int(cfg["calibration_experiments"]),
                                int(cfg["seed"]))  # fmt: skip
    variants = {"mismatch (full)": EmulatedPlant(seed, kind="mismatch")}
    for part in MISMATCH_PARTS:
        variants[f"without {part}"] = EmulatedPlant(seed, kind="mismatch", mismatch_off=(part,))
    variants["in-class"] = EmulatedPlant(seed)
    print("ORACLE: reads the plant's hidden parameters (benchmark only, never in rehearse)")
    print(f"{args.folder}: {len(ids)} held-out rows, plant seed {seed}; the twin's decisions "
          f"(p_after >= 0.5) against the recorded outcomes: F0.5 {_f05(twin, y):.3f}, "
          f"agreement {np.mean(twin == y):.3f}")  # fmt: skip
    print(
        f"{'plant variant':22s} {'share':>6s} {'F0.5 twin':>10s} {'vs full':>8s} "
        f"{'agree':>6s} {'vs full':>8s} {'rows unlike full':>17s}"
    )
    t0, full = time.perf_counter(), None
    for name, plant in variants.items():
        share = _shares(plant, design, ids, seed, args.n, args.workers)
        major = (share >= 0.5).astype(int)
        f05, agree = _f05(twin, major), float(np.mean(twin == major))
        if full is None:
            full = (major, f05, agree)
        print(
            f"{name:22s} {share.mean():6.3f} {f05:10.3f} {f05 - full[1]:+8.3f} "
            f"{agree:6.3f} {agree - full[2]:+8.3f} {int(np.sum(major != full[0])):17d}"
        )
    print(
        f"{args.n} reruns per row and variant, {time.perf_counter() - t0:.0f} s on "
        f"{args.workers} workers"
    )


if __name__ == "__main__":
    main()
