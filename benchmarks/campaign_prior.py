"""Object calibration's prior, measured on campaigns' own physical experiments: does a twin
whose proxies move from the shipped features (and keep them on a face with too few rows)
predict rows it never saw better than one whose proxies move from the plain body?

    PYTHONPATH=src .venv/bin/python benchmarks/campaign_prior.py FOLDER [FOLDER ...]

Each FOLDER is a finished calibration campaign's (``cps campaign``; it holds
``plant_journal.jsonl``, every E^P it ran on the floor's units, and ``rehearsal.json``, its
request). Its calibration E^P are split as the campaign split them; every variant's proxies
are fitted on the training rows only (the rehearsal's object calibration, as the campaign ran it)
and every variant replays the same rows it never saw: the campaign's held-out rows and its
validation E^P (4 per object's best and worst state, chosen by the campaign's own twin, the
``plain/1`` variant's: a set that favours it). With ``--plant-seeds`` (one per folder, the
floor's plant) each folder also gets ``--test-experiments`` fresh E^P of the emulated plant of
that seed and ``--plant-kind`` (the floor's physical units' hidden values; the study's random
design over the campaign's objects, its own seed stream): an unbiased test set, scored
apart. Variants:

- ``uncalibrated``: the built-in cores with their shipped features (the baseline);
- ``plain/1``: what campaigns have done so far (from the plain body, every face tried);
- ``shipped/1``, ``shipped/2``: from each face's shipped feature, a face searched only with
  at least 1 or 2 training rows.

Prints per folder and pooled over the folders: each variant's Brier score and F0.5 (the
rehearsal's: the mean over runs of each run's F0.5) on the unseen rows, and its paired
differences from the uncalibrated twin with percentile-bootstrap 95 % intervals (rows
resampled together): better, worse or undecided; and its within-object concordance (of the
pairs of one object's rows where one succeeded and one failed, the share where the twin gave
the success the higher share: what ranking an object's states needs), objects resampled.
Writes ``--out`` (JSON) and beside it the predictions (``.npz``) if given.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "src"))

VARIANTS = (("uncalibrated", None, 0), ("plain/1", "plain", 1), ("shipped/1", "shipped", 1),
            ("shipped/2", "shipped", 2))  # fmt: skip
BOOTSTRAP = 4000


def journal_rows(folder: Path) -> tuple[list[dict], list[dict]]:
    """(calibration rows in request order, validation rows), experiment ids made unique."""
    calls: dict[int, dict[int, dict]] = {}
    for line in (folder / "plant_journal.jsonl").read_text().splitlines():
        try:
            entry = json.loads(line)
        except json.JSONDecodeError:
            continue
        call, i = (int(v) for v in entry["key"].split(":"))
        calls.setdefault(call, {})[i] = entry["row"]
    if 0 not in calls:
        raise SystemExit(f"{folder}: no calibration E^P in its journal")
    out = []
    for call in (0, 1):
        rows = [dict(calls.get(call, {})[i]) for i in sorted(calls.get(call, {}))]
        out.append(rows)
    for n, row in enumerate(out[0] + out[1]):
        row["experiment_id"] = n
    return out[0], out[1]


def fit_variant(train: list[dict], prior: str, min_rows: int, cfg: dict, scene,
                work: Path) -> dict[str, str]:  # fmt: skip
    """Object id → proxy file of one variant, fitted on `train` by the rehearsal's own object
    calibration (`_calibrate_objects`, as the campaign ran it: its objects, depths, runs and
    seed; the campaign's counter-measures, no scale)."""
    from transfertwin.cps.apps import CAMPAIGN_MEASURES
    from transfertwin.rehearsal import RehearsalConfig
    from transfertwin.rehearsal._rehearse import _calibrate_objects, _Run

    rcfg = RehearsalConfig(
        plant_seed=0, objects=tuple(cfg["objects"]),
        calibration_experiments=cfg["calibration_experiments"], runs=cfg["runs"],
        holdout=cfg["holdout"], depths_mm=tuple(cfg["depths_mm"]), seed=cfg["seed"],
        workers=cfg["workers"], object_prior=prior, min_face_rows=min_rows,
    )  # fmt: skip
    run = _Run(rcfg, None, [], train, [], lambda stage: None, lambda done, total: None)
    object_map, _ = _calibrate_objects(run, frozenset(CAMPAIGN_MEASURES), scene, work)
    return object_map


def scores(p_runs: np.ndarray, y: np.ndarray, idx: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Brier score and F0.5 (mean over runs) of each resample `idx` (B, n)."""
    from transfertwin.rehearsal._scoring import _f05_rows

    p = p_runs.mean(axis=0)
    brier = ((p[idx] - y[idx]) ** 2).mean(axis=1)
    f05 = np.mean([_f05_rows(run[idx].astype(bool), y[idx].astype(bool)) for run in p_runs],
                  axis=0)  # fmt: skip
    return brier, f05


def concordance(p_runs: np.ndarray, y: np.ndarray, objects: np.ndarray) -> dict[str, tuple]:
    """Per object, (concordant, pairs): of the pairs of its rows where one succeeded and the
    other failed, those where the success had the higher predicted share (a tie counts ½).
    The policy ranks an object's states: this, not the Brier score, is what it needs."""
    p = p_runs.mean(axis=0)
    out = {}
    for obj in np.unique(objects):
        mine = objects == obj
        win, lose = p[mine & (y == 1)], p[mine & (y == 0)]
        if win.size and lose.size:
            diff = win[:, None] - lose[None, :]
            out[str(obj)] = (float((diff > 0).sum() + 0.5 * (diff == 0).sum()), diff.size)
    return out


def report(name: str, preds: dict[str, np.ndarray], y: np.ndarray,
           objects: np.ndarray | None = None) -> dict:  # fmt: skip
    """Print and return each variant's scores and its paired differences from the baseline
    (with `objects`, also the within-object concordance, objects resampled)."""
    rng = np.random.default_rng([0, 0x50524952])
    full = np.arange(len(y))[None, :]
    idx = rng.integers(0, len(y), (BOOTSTRAP, len(y)))
    base_b, base_f = scores(preds["uncalibrated"], y, idx)
    out = {"rows": len(y), "successes": int(y.sum()), "variants": {}}
    print(f"{name}: {len(y)} unseen rows ({int(y.sum())} successes)")
    for var, p in preds.items():
        b0, f0 = scores(p, y, full)
        b, f = scores(p, y, idx)
        db = np.quantile(b - base_b, (0.025, 0.975))
        df = np.quantile(f - base_f, (0.025, 0.975))

        def verdict(lo, hi, lower_is_better):
            if lo <= 0 <= hi:
                return "undecided"
            return "better" if (hi < 0) == lower_is_better else "worse"

        entry = {"brier": float(b0[0]), "f05": float(f0[0])}
        line = f"  {var:<13} Brier {b0[0]:.3f}  F0.5 {f0[0]:.3f}"
        if var != "uncalibrated":
            entry |= {"brier_minus_uncalibrated": [float(v) for v in db],
                      "f05_minus_uncalibrated": [float(v) for v in df],
                      "brier_verdict": verdict(*db, True),
                      "f05_verdict": verdict(*df, False)}  # fmt: skip
            line += (f"   Brier − uncalibrated [{db[0]:+.3f}, {db[1]:+.3f}] "
                     f"{entry['brier_verdict']}; F0.5 − uncalibrated [{df[0]:+.3f}, "
                     f"{df[1]:+.3f}] {entry['f05_verdict']}")  # fmt: skip
        print(line, flush=True)
        out["variants"][var] = entry
    if objects is not None:
        conc = {v: concordance(p, y, objects) for v, p in preds.items()}
        names = sorted(conc["uncalibrated"])
        pick = np.random.default_rng([0, 0x434F4E43]).integers(0, len(names),
                                                               (BOOTSTRAP, len(names)))

        def share(c: dict, idx: np.ndarray) -> np.ndarray:
            k = np.array([c[o][0] for o in names])[idx].sum(axis=-1)
            n = np.array([c[o][1] for o in names])[idx].sum(axis=-1)
            return k / n

        base = share(conc["uncalibrated"], pick)
        for var, c in conc.items():
            c0 = float(share(c, np.arange(len(names))))
            line = f"  {var:<13} within-object concordance {c0:.3f} ({len(names)} objects)"
            out["variants"][var]["concordance"] = c0
            if var != "uncalibrated":
                d = np.quantile(share(c, pick) - base, (0.025, 0.975))
                v = "undecided" if d[0] <= 0 <= d[1] else ("better" if d[0] > 0 else "worse")
                out["variants"][var] |= {"concordance_minus_uncalibrated": [float(x) for x in d],
                                         "concordance_verdict": v}  # fmt: skip
                line += f"   − uncalibrated [{d[0]:+.3f}, {d[1]:+.3f}] {v}"
            print(line, flush=True)
    return out


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("folders", nargs="+", type=Path, help="finished campaigns' folders")
    ap.add_argument("--work", type=Path, default=Path("/tmp/campaign-prior"),
                    help="where the variants' proxies go")
    ap.add_argument("--out", type=Path, help="write the figures as JSON")
    ap.add_argument("--plant-seeds", help="the floors' plant seeds, one per folder: adds an "
                                          "unbiased test set from that plant")  # fmt: skip
    ap.add_argument("--plant-kind", default="mismatch", choices=("in-class", "mismatch"))
    ap.add_argument("--test-experiments", type=int, default=200)
    ap.add_argument("--variants", default=",".join(v[0] for v in VARIANTS),
                    help="a subset of " + ", ".join(v[0] for v in VARIANTS))
    args = ap.parse_args()
    seeds = [int(v) for v in args.plant_seeds.split(",")] if args.plant_seeds else []
    if seeds and len(seeds) != len(args.folders):
        raise SystemExit("--plant-seeds: one seed per folder")
    chosen = args.variants.split(",")
    variants = [v for v in VARIANTS if v[0] in chosen]
    if "uncalibrated" not in chosen or len(variants) != len(chosen):
        raise SystemExit("--variants: names of VARIANTS, uncalibrated among them")

    from transfertwin.cps.apps import CAMPAIGN_MEASURES
    from transfertwin.rehearsal import holdout_split, twin_scene
    from transfertwin.rehearsal._scoring import run_predictions
    from transfertwin.sim import SceneConfig
    from transfertwin.study.calibration import calibrate

    scene = twin_scene(SceneConfig(), frozenset(CAMPAIGN_MEASURES))
    sets = ("campaign", "plant") if seeds else ("campaign",)
    pooled = {s: {v[0]: [] for v in variants} for s in sets}
    pooled_y: dict[str, list[np.ndarray]] = {s: [] for s in sets}
    pooled_o: dict[str, list[np.ndarray]] = {s: [] for s in sets}
    doc: dict = {"folders": {}}
    for n, folder in enumerate(args.folders):
        cfg = json.loads((folder / "rehearsal.json").read_text())["config"]
        calib, validation = journal_rows(folder)
        train, test = holdout_split(calib, cfg["holdout"], cfg["seed"])
        unseen = {"campaign": list(test) + validation}
        print(f"{folder}: {len(calib)} calibration E^P ({len(train)} training, "
              f"{len(test)} held out), {len(validation)} validation E^P", flush=True)
        if seeds:
            from transfertwin.plant import EmulatedPlant
            from transfertwin.rehearsal import calibration_design

            design = calibration_design(cfg["objects"], args.test_experiments, cfg["seed"],
                                        "test")  # fmt: skip
            plant = EmulatedPlant(seeds[n], kind=args.plant_kind)
            rows = plant.run(design, workers=cfg["workers"])
            for i, row in enumerate(rows):
                row["experiment_id"] = 100_000 + i
            unseen["plant"] = rows
            print(f"  + {len(rows)} E^P of the {args.plant_kind} plant of seed {seeds[n]} "
                  "(the study's random design): the unbiased test set", flush=True)
        preds: dict[str, dict[str, np.ndarray]] = {s: {} for s in sets}
        for var, prior, min_rows in variants:
            work = args.work / folder.name / var.replace("/", "-")
            omap = (None if prior is None else
                    fit_variant(train, prior, min_rows, cfg, scene, work))
            for s in sets:
                result = calibrate(unseen[s], runs=cfg["runs"], scene=scene, object_map=omap,
                                   seed=cfg["seed"], workers=cfg["workers"])  # fmt: skip
                preds[s][var] = run_predictions(result)
                pooled[s][var].append(preds[s][var])
        doc["folders"][str(folder)] = {}
        for s in sets:
            y = np.array([int(r["success"]) for r in unseen[s]])
            label = {"campaign": "campaign's held-out and validation E^P",
                     "plant": "fresh plant E^P (unbiased)"}[s]  # fmt: skip
            objs = np.array([f"{n}:{r['object_id']}" for r in unseen[s]])
            doc["folders"][str(folder)][s] = report(f"{folder}, {label}", preds[s], y, objs)
            pooled_y[s].append(y)
            pooled_o[s].append(objs)
    if len(args.folders) > 1:
        doc["pooled"] = {
            s: report(f"pooled, {s}", {v: np.concatenate(p, axis=1) for v, p in
                                       pooled[s].items()}, np.concatenate(pooled_y[s]),
                      np.concatenate(pooled_o[s]))
            for s in sets
        }  # fmt: skip
    if args.out:
        args.out.write_text(json.dumps(doc, indent=2) + "\n")
        arrays = {f"{s}_{v}": np.concatenate(p, axis=1) for s in sets
                  for v, p in pooled[s].items()}  # fmt: skip
        arrays |= {f"{s}_y": np.concatenate(pooled_y[s]) for s in sets}
        arrays |= {f"{s}_objects": np.concatenate(pooled_o[s]) for s in sets}
        np.savez(args.out.with_suffix(".npz"), **arrays)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
