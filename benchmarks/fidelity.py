"""Fidelity of the twin against the 191 real experiments, beside the baselines.

Prints, in one run: the gap-area geometry against the measured `gap_area_cm2` (R², bias),
then the twin with calibrated proxy objects (per core and face) against the always-success
predictor and a logistic regression, in-sample and in repeated stratified 5-fold
cross-validation (every choice made on training folds only), and each core's simulated
success share against the real Clopper–Pearson 95 % interval. Targets (issue: fidelity):
twin in-sample F0.5 >= 0.84 with recall <= 0.95; twin CV F0.5 above the logistic baseline;
with `--study STORE` (e.g. `out/quick.sqlite` of `./dev.sh run`: o1, o18, o23, o32 × the
30°-step grid on the default profile and the shipped cores), at least 3 of 4 cores with both
outcomes and an overall success share between 0.4 and 0.9.

    python benchmarks/fidelity.py [--objects DIR] [--runs 2] [--workers 2] [--study STORE]

`--objects DIR` reuses `transfertwin calibrate object` outputs; missing cores are fitted
into DIR first (about 2 minutes per core on 2 workers).
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
    candidates_path,
    evaluate_predictions,
    fit_proxy,
    fitted_candidates,
    save_candidates,
)
from transfertwin.study.fullstate import clopper_pearson

DEPTHS_M = [d / 1000 for d in (6, 10, 14, 18, 20, 22, 24, 26, 28)]


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


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--objects", default="out/fidelity-objects")
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
    folder = Path(args.objects)
    shifts = [float(v) / 1000 for v in args.com_shifts_mm.split(",") if v.strip()]
    for obj in sorted({str(r["object_id"]) for r in rows}, key=lambda o: int(o[1:])):
        if not candidates_path(folder, obj).is_file():
            fit = fit_proxy(rows, obj, depths_m=DEPTHS_M, work_dir=folder / "candidates",
                            scene=SceneConfig(), runs=args.runs, workers=args.workers,
                            penalty=args.penalty, shifts_m=shifts,
                            shift_penalty=args.mass_penalty)  # fmt: skip
            write_proxy(fit.spec, folder / f"{obj}.proxy.json")
            save_candidates(fit, candidates_path(folder, obj))
    candidates, groups = fitted_candidates(folder, rows)
    ev = evaluate_predictions(rows, candidates, folds=5, repeats=5, seed=0,
                              penalty=args.penalty, groups=groups,
                              shift_penalty=args.mass_penalty)  # fmt: skip
    print(f"{'predictor':20s} {'F0.5':>6s} {'prec':>6s} {'recall':>6s} {'brier':>6s}")
    keys = ("base_rate", "logistic_in_sample", "logistic_cv", "twin_in_sample", "twin_cv",
            "hybrid_in_sample", "hybrid_cv")  # fmt: skip
    for key in keys:
        f = ev.figures[key]
        print(f"{key:20s} {f['f05']:6.3f} {f['precision']:6.3f} {f['recall']:6.3f} "
              f"{f['brier']:6.3f}")  # fmt: skip
    hcv = ev.figures["hybrid_cv"]
    print(f"hybrid CV (beside the twin, not instead): F0.5 {hcv['f05']:.3f} "
          f"± {hcv['f05_std']:.3f} vs twin {ev.figures['twin_cv']['f05']:.3f} "
          f"± {ev.figures['twin_cv']['f05_std']:.3f}")  # fmt: skip
    tin, tcv, lcv = ev.figures["twin_in_sample"], ev.figures["twin_cv"], ev.figures["logistic_cv"]
    print(
        f"target in-sample F0.5 >= 0.84 and recall <= 0.95: "
        f"{'met' if tin['f05'] >= 0.84 and tin['recall'] <= 0.95 else 'not met'}"
    )
    print(
        f"target CV F0.5 above logistic CV: {tcv['f05']:.3f} vs {lcv['f05']:.3f} "
        f"({'met' if tcv['f05'] > lcv['f05'] else 'not met'})"
    )
    print(f"chosen proxies (in-sample): {ev.chosen}")
    y = np.array([int(r["success"]) for r in rows])
    objects = np.array([str(r["object_id"]) for r in rows])
    for obj in sorted(set(objects), key=lambda o: int(o[1:])):
        m = objects == obj
        ci = clopper_pearson(int(y[m].sum()), int(m.sum()))
        sim = float(ev.twin_p[m].mean())
        inside = ci.low <= sim <= ci.high
        print(
            f"{obj}: real {y[m].mean():.2f} [{ci.low:.2f}, {ci.high:.2f}]  twin {sim:.2f}  "
            f"{'inside' if inside else 'outside'}"
        )


if __name__ == "__main__":
    main()
