"""Fidelity of the twin against the 191 real experiments, beside the baselines.

Prints, in one run: the gap-area geometry against the measured `gap_area_cm2` (R², bias);
then the headline (issue 29): nested cross-validation over `--cv-seeds` stratified 5-fold
partitions in which every choice — which candidate folder (scene variant: pulley shape and
radius, R, contact settings), the depth penalty, the proxy per core and face, the shrinkage,
each threshold, the logistic model's L2 strength — is made on the training rows alone; F0.5
and Brier of the twin, the (object, face) rate table, the (object, face, conveyor) rate
table with shrinkage, the logistic model and always-success, each with a row-bootstrap 95 %
interval; the paired twin-minus-table differences; the noise ceiling from near-repeats;
leave-one-cell-out figures; each core's raw simulated share against the real
Clopper–Pearson interval; and which choices remain made on all rows. After it, the single
folder's 5 × 5 figures of before (penalty fixed), which are not the headline.

    python benchmarks/fidelity.py [--objects DIR[,DIR...]] [--cv-seeds 20] [--study STORE]

The default `--objects` are the four candidate folders shipped under `benchmarks/results/`
(`2026-11-23-fidelity-proxies/calibrated-r25` and three of `2026-11-23-fidelity-runs/`;
nothing is simulated; about 4 minutes on one core). A folder that lacks a core's
candidates is fitted first (`calibrate object`, about 2 minutes per core on 2 workers).
With `--study STORE` (e.g. `out/quick.sqlite` of `./dev.sh run`) it also checks the grid
targets: at least 3 of 4 cores with both outcomes and an overall share between 0.4 and 0.9.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from transfertwin.data import calibration_csv_path
from transfertwin.objects import write_proxy
from transfertwin.sim import GapAreaLayout, LayoutConfig, SceneConfig, gap_areas_cm2
from transfertwin.store import DOCKING_ERROR_COLUMNS, read_results
from transfertwin.study.calibration import (
    Variant,
    candidates_path,
    evaluate_predictions,
    fidelity_report,
    fit_proxy,
    fitted_candidates,
    report_lines,
    save_candidates,
)

DEPTHS_M = [d / 1000 for d in (6, 10, 14, 18, 20, 22, 24, 26, 28)]
SHIPPED = ",".join(f"benchmarks/results/{f}" for f in (
    "2026-11-23-fidelity-proxies/calibrated-r25",
    "2026-11-23-fidelity-runs/prism-r12.5-R4",
    "2026-11-23-fidelity-runs/prism-r12.5-R6",
    "2026-11-23-fidelity-runs/prism-r12.5-R6-mccd-auto"))  # fmt: skip


def _gap_fit(rows) -> None:
    real = np.array([float(r["gap_area_cm2"]) for r in rows])
    for label, geo in (("scene belts (195 mm)", GapAreaLayout.from_layout(LayoutConfig())),
                       ("fitted strip (246 mm)", GapAreaLayout.fitted())):  # fmt: skip
        errors = [[float(r[c]) for c in DOCKING_ERROR_COLUMNS] for r in rows]
        sim = gap_areas_cm2(geo, np.array(errors), [str(r["conveyor"]) for r in rows])
        r2 = 1 - np.sum((real - sim) ** 2) / np.sum((real - real.mean()) ** 2)
        print(f"gap area, {label:22s} R2 {r2:7.4f}  bias {np.mean(sim - real):+6.2f} cm2")


def _study_grid(path: str) -> None:
    """Success shares per core of a finished study store, against the grid targets."""
    rows = read_results(path)
    objects = sorted({str(r["object_id"]) for r in rows}, key=lambda o: (len(o), o))
    mixed = 0
    for obj in objects:
        ok = np.array([int(r["success"]) for r in rows if r["object_id"] == obj])
        mixed += 0 < ok.sum() < len(ok)
        print(f"study {obj}: success share {ok.mean():.2f} over {len(ok)} runs")
    share = float(np.mean([int(r["success"]) for r in rows]))
    met = mixed >= min(3, len(objects)) and 0.4 <= share <= 0.9
    print(f"target study grid: {mixed}/{len(objects)} cores with both outcomes (>= 3), "
          f"overall share {share:.2f} (0.4..0.9): {'met' if met else 'not met'}")  # fmt: skip


def _fit_missing(folder: Path, rows, args, shifts) -> None:
    for obj in sorted({str(r["object_id"]) for r in rows}, key=lambda o: int(o[1:])):
        if not candidates_path(folder, obj).is_file():
            fit = fit_proxy(rows, obj, depths_m=DEPTHS_M, work_dir=folder / "candidates",
                            scene=SceneConfig(), runs=args.runs, workers=args.workers,
                            penalty=args.penalty, shifts_m=shifts,
                            shift_penalty=args.mass_penalty)  # fmt: skip
            write_proxy(fit.spec, folder / f"{obj}.proxy.json")
            save_candidates(fit, candidates_path(folder, obj))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--objects", default=SHIPPED,
                        help="candidate folders, comma-separated (default: the shipped four)")
    parser.add_argument("--cv-seeds", type=int, default=20)
    parser.add_argument("--resamples", type=int, default=2000)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--runs", type=int, default=2)
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--penalty", type=float, default=0.02)
    parser.add_argument("--mass-penalty", type=float, default=0.02)
    parser.add_argument("--com-shifts-mm", default="",
                        help="centre-of-mass shifts to search in fits (default: none)")  # fmt: skip
    parser.add_argument("--study", help="a finished study store to check the grid targets on")
    args = parser.parse_args()
    if args.study:
        _study_grid(args.study)
    rows = read_results(calibration_csv_path())
    _gap_fit(rows)
    shifts = [float(v) / 1000 for v in args.com_shifts_mm.split(",") if v.strip()]
    variants = []
    for name in args.objects.split(","):
        folder = Path(name)
        _fit_missing(folder, rows, args, shifts)
        candidates, groups = fitted_candidates(folder, rows)
        variants.append(Variant(folder.name, candidates, groups))
    report = fidelity_report(rows, variants, seeds=args.cv_seeds, seed=args.seed,
                             shift_penalty=args.mass_penalty,
                             n_resamples=args.resamples)  # fmt: skip
    print("\n".join(report_lines(report)))
    scores = report["scores"]
    print(f"baseline: (object, face) rate table F0.5 {scores['table_object_face']['f05']:.3f}; "
          f"twin/table F0.5 ratio {scores['twin']['f05'] / scores['table_object_face']['f05']:.3f}"
          f", Brier ratio {scores['twin']['brier'] / scores['table_object_face']['brier']:.3f}")
    first = variants[0]
    ev = evaluate_predictions(rows, first.candidates, folds=5, repeats=5, seed=args.seed,
                              penalty=args.penalty, groups=first.groups,
                              shift_penalty=args.mass_penalty)  # fmt: skip
    print(f"single folder {first.label}, 5 x 5 CV with its penalty fixed (not the headline):")
    for key in ("base_rate", "logistic_cv", "twin_in_sample", "twin_cv", "hybrid_cv"):
        f = ev.figures[key]
        print(f"  {key:18s} F0.5 {f['f05']:6.3f}  precision {f['precision']:6.3f}  "
              f"recall {f['recall']:6.3f}  Brier {f['brier']:6.3f}")  # fmt: skip


if __name__ == "__main__":
    main()
