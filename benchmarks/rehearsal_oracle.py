"""ORACLE ceiling of a rehearsal's held-out F0.5 — reads the plant's hidden parameters.

**Benchmark only.** This script opens the emulated plant's private experiment machinery
(`EmulatedPlant._jobs`, `transfertwin.plant._plant._run_job`), which no part of the twin or
of `transfertwin rehearse` may do. It answers one question: how high can *any* twin's F0.5 on
a rehearsal's held-out plant experiments be, given the plant's own outcome noise?

For each rehearsal folder (``rehearsal.json``, the plant's seed in ``plant.secret`` beside
it, ``plant_calibration.csv`` and, with
``--test-experiments``, ``plant_test.csv``; a curve folder's ``K*/`` sub-folders in turn) it
rebuilds the held-out rows exactly as `rehearse` chose them and the plant's own jobs for them
(the first experiments of a fresh plant of the same seed), then prints beside the twin's F0.5
(before and after calibration) and the always-success baseline:

- ``flips``: held-out rows whose recorded outcome the plant flipped (its outcome noise), and
  ``F0.5 exact``: the predictor that knows the plant's hidden parameters *and* the very
  placement draws of each experiment (it errs only on the flipped rows).
- ``F0.5 oracle``: the predictor that knows the hidden parameters but not the placement draws
  (what the best possible twin can know): the plant's simulation of each held-out row at its
  logged state and docking error, N times with fresh placement seeds, no flips; the mean
  over the N runs of each run's F0.5 (as ``f05_*``), and the majority vote (the plant's own
  share per row thresholded at 0.5, as rehearsal.json's ``thresholded`` block thresholds the
  twin), with the Brier score of that share.
- 95 % percentile-bootstrap intervals over the held-out rows (`f05_intervals`, 2000
  resamples); the gap's verdict "within 0.05" is met / missed / undecided by its interval.
- ``oracle_rows.csv`` in the folder: per held-out row the outcome, the reruns' share, the
  majority and the twin's decision (for paired comparisons of two rehearsals' gaps).

    python benchmarks/rehearsal_oracle.py DIR [--n 6] [--workers 2]
"""

from __future__ import annotations

import argparse
import csv
import dataclasses
import json
import multiprocessing as mp
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np

from transfertwin.plant import PLANT_SEED_FILE, EmulatedPlant, read_plant_seed
from transfertwin.plant._plant import _run_job  # ORACLE: private plant machinery
from transfertwin.rehearsal import calibration_design, f05_intervals, holdout_split


def _rows(path: Path) -> list[dict[str, object]]:
    rows: list[dict[str, object]] = []
    for r in csv.DictReader(path.open()):
        row: dict[str, object] = dict(r)
        for c in ("experiment_id", "theta_deg", "success"):
            row[c] = int(r[c])
        for c in ("dock_err_x_mm", "dock_err_y_mm", "dock_err_theta_deg", "gap_area_cm2"):
            row[c] = float(r[c])
        rows.append(row)
    return rows


def _f05(pred: np.ndarray, y: np.ndarray) -> float:
    pred, y = pred.astype(bool), y.astype(bool)
    tp, fp, fn = (pred & y).sum(), (pred & ~y).sum(), (~pred & y).sum()
    return 0.0 if tp == 0 else float(1.25 * tp / (1.25 * tp + 0.25 * fn + fp))


def rerun_wins(jobs, tag: int, plant_seed: int, n: int, workers: int) -> np.ndarray:
    """(len(jobs), n) outcomes of each plant job run `n` times again with fresh placement
    seeds (from `tag`, the plant seed, the experiment id and the rerun) and no outcome flip."""
    reruns = []
    for j in jobs:
        for i in range(n):
            ss = np.random.SeedSequence([tag, plant_seed, j.experiment_id, i])
            seeds = tuple(int(w) for w in ss.generate_state(len(j.seeds)))
            reruns.append(dataclasses.replace(j, seeds=seeds, flip_u=1.0))
    with ProcessPoolExecutor(workers, mp_context=mp.get_context("spawn")) as pool:
        wins = [int(row["success"]) for row, _ in pool.map(_run_job, reruns)]
    return np.array(wins).reshape(len(jobs), n)


def _twin_decisions(folder: Path, doc: dict, test: list[dict[str, object]]) -> np.ndarray | None:
    """The calibrated twin's one decision per held-out row (``p_after >= t`` in
    ``held_out_predictions.csv``, t the threshold the rehearsal recorded for it: chosen on
    the training rows for R > 1, else 0.5), (1, n) in the order of `test`; None without
    the file."""
    path = folder / "held_out_predictions.csv"
    if not path.is_file():
        return None
    t = float((doc.get("thresholded") or {}).get("threshold_after", 0.5))
    p = {int(r["experiment_id"]): float(r["p_after"]) for r in csv.DictReader(path.open())}
    return np.array([[int(p[int(r["experiment_id"])] >= t) for r in test]])


def oracle(folder: Path, n: int, workers: int) -> dict[str, object]:
    doc = json.loads((folder / "rehearsal.json").read_text())
    cfg = doc["config"]
    k = int(cfg["calibration_experiments"])
    h, objects, seed = int(cfg.get("test_experiments", 0)), tuple(cfg["objects"]), int(cfg["seed"])
    rows = _rows(folder / "plant_calibration.csv")
    if h:  # separate test experiments: ids 0..H-1, then the K calibration experiments
        test = _rows(folder / "plant_test.csv")
        rows = test + rows
        design = calibration_design(objects, h, seed, "test") + calibration_design(objects, k, seed)
    else:  # the split `rehearse` made of the K experiments (ids 0..K-1)
        _, test = holdout_split(rows, float(cfg["holdout"]), seed)
        design = calibration_design(objects, k, seed)
    plant_seed = read_plant_seed(folder / PLANT_SEED_FILE)  # rehearsal.json does not hold it
    plant = EmulatedPlant(plant_seed, kind=cfg.get("plant_kind", "in-class"),
                          mismatch_off=tuple(cfg.get("mismatch_off", ())))  # fmt: skip
    jobs = plant._jobs(design)
    by_id = {j.experiment_id: j for j in jobs}
    for r in rows:  # the rebuilt jobs are the plant's: same state and logged docking error
        j = by_id[int(r["experiment_id"])]
        assert (j.request.face, j.request.theta_deg) == (r["face"], r["theta_deg"])
        assert [round(v, 2) for v in j.error_mm_deg] == [
            r["dock_err_x_mm"], r["dock_err_y_mm"], r["dock_err_theta_deg"]
        ]  # fmt: skip
    test_jobs = [by_id[int(r["experiment_id"])] for r in test]
    flip_p = test_jobs[0].scene.flip_p
    flipped = np.array([j.flip_u < flip_p for j in test_jobs])
    y = np.array([int(r["success"]) for r in test])
    per_run = rerun_wins(test_jobs, 0x4F52434C, plant_seed, n, workers).T  # (N, n)
    majority = (per_run.mean(axis=0) >= 0.5).astype(int)[None, :]
    exact = np.where(flipped, 1 - y, y)[None, :]  # the plant's physics before the flip
    preds = {"oracle": per_run, "majority": majority, "exact": exact}
    twin = _twin_decisions(folder, doc, test)
    if twin is not None:
        preds["twin"] = twin
    ci = f05_intervals(preds, y, differences=[("majority", "twin")] if twin is not None else [])
    return {
        "K": k, "held_out": len(test), "flip_p": flip_p, "flipped": int(flipped.sum()),
        "flipped_all": int(sum(j.flip_u < flip_p for j in jobs)), "rows": len(rows),
        "f05_before": doc["f05_before"], "f05_after": doc["f05_after"],
        "f05_base_rate": doc["f05_base_rate"],
        "exact": _f05(exact[0], y), "oracle": float(np.mean([_f05(p, y) for p in per_run])),
        "majority": _f05(majority[0], y), "ci": ci,
        "twin": None if twin is None else _f05(twin[0], y),
        "brier": float(np.mean((per_run.mean(axis=0) - y) ** 2)),
        "uncertain_rows": int(((per_run.mean(0) > 0) & (per_run.mean(0) < 1)).sum()),
        "per_row": [(int(r["experiment_id"]), int(y[i]), float(per_run[:, i].mean()),
                     int(majority[0, i]), "" if twin is None else int(twin[0, i]))
                    for i, r in enumerate(test)],
    }  # fmt: skip


def verdict(interval, limit: float) -> str:
    """'met' when the whole interval lies at or under `limit`, 'missed' when it lies wholly
    above it, 'undecided' otherwise."""
    lo, hi = interval
    return "met" if hi <= limit else "missed" if lo > limit else "undecided"


def write_rows(folder: Path, o: dict[str, object]) -> Path:
    """``oracle_rows.csv`` beside the rehearsal: per held-out row its recorded outcome, the
    plant's rerun share, the majority and the twin's decision, so that gaps of two
    rehearsals on the same states can be compared paired (`f05_intervals(differences=...)`)."""
    path = folder / "oracle_rows.csv"
    with path.open("w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(["experiment_id", "success", "oracle_share", "majority", "twin"])
        w.writerows(o["per_row"])  # type: ignore[arg-type]
    return path


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("folder", type=Path, help="a rehearsal folder or a curve folder (K*/)")
    ap.add_argument("--n", type=int, default=6, help="plant reruns per held-out row")
    ap.add_argument("--workers", type=int, default=2)
    args = ap.parse_args()
    folders = sorted(
        (p for p in args.folder.glob("K*") if (p / "plant_calibration.csv").is_file()),
        key=lambda p: int(p.name[1:]),
    ) or [args.folder]
    print("ORACLE: reads the plant's hidden parameters (benchmark only, never in rehearse)")
    for folder in folders:
        o = oracle(folder, args.n, args.workers)
        write_rows(folder, o)
        ci = o["ci"]
        print(
            f"K={o['K']}: held-out {o['held_out']}, flipped {o['flipped']} "
            f"(all {o['rows']} rows: {o['flipped_all']}, flip p {o['flip_p']:.3f}), rows whose "
            f"outcome varies between plant reruns {o['uncertain_rows']}\n"
            f"  twin before {o['f05_before']:.3f}, after {o['f05_after']:.3f}; always-success "
            f"{o['f05_base_rate']:.3f} [{ci['base_rate'][0]:.2f}, {ci['base_rate'][1]:.2f}]\n"
            f"  ORACLE (N={args.n} reruns) {o['oracle']:.3f} "
            f"[{ci['oracle'][0]:.2f}, {ci['oracle'][1]:.2f}], majority {o['majority']:.3f} "
            f"[{ci['majority'][0]:.2f}, {ci['majority'][1]:.2f}]; exact (errs only on flips) "
            f"{o['exact']:.3f} [{ci['exact'][0]:.2f}, {ci['exact'][1]:.2f}]; "
            f"twin after / oracle {o['f05_after'] / o['oracle']:.2f}\n"
            f"  ORACLE Brier of its rerun shares {o['brier']:.3f} (compare the twin's "
            f"'thresholded' block in rehearsal.json: majority F0.5 and Brier)"
        )
        if o["twin"] is not None:
            gap = ci["majority_minus_twin"]
            print(f"  gap: oracle majority - twin after (one decision per row) "
                  f"{o['majority'] - o['twin']:+.3f} [{gap[0]:+.3f}, {gap[1]:+.3f}] (paired "
                  f"bootstrap over the held-out rows); within 0.05: "
                  f"{verdict(gap, 0.05)}")  # fmt: skip


if __name__ == "__main__":
    main()
