"""Replay extra depth candidates per object/face (same seeds as calibrate object: common
random numbers), saved as OUT/<obj>.candidates.npz (only the given depths; twin_cv.py merges).

usage: replay_candidates.py --profile P --out DIR --runs R --spec "o1:front:5.5,6.5;o18:front:6.5" """
import argparse, time
from pathlib import Path
import numpy as np
from transfertwin.data import calibration_csv_path
from transfertwin.store import read_results
from transfertwin.study.calibration._object_fit import _candidate
from transfertwin.study.calibration._replay import replay_specs
from transfertwin.study.experiment import load_profile, run_rows


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--profile", required=True)
    ap.add_argument("--out", required=True)
    ap.add_argument("--runs", type=int, default=2)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--first-run", type=int, default=0)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--spec", required=True)
    a = ap.parse_args()
    _, scene = load_profile(a.profile)
    rows = read_results(calibration_csv_path())
    out = Path(a.out); work = out / "candidates"; work.mkdir(parents=True, exist_ok=True)
    plan = {}
    for part in a.spec.split(";"):
        obj, face, ds = part.split(":")
        plan.setdefault(obj, {})[face] = [float(v) / 1000 for v in ds.split(",")]
    specs, where, face_rows = [], {}, {}
    for obj, faces in plan.items():
        for face, depths in faces.items():
            fr = [r for r in rows if r["object_id"] == obj and r["face"] == face]
            face_rows[(obj, face)] = fr
            for k, d in enumerate(depths):
                name, ref = _candidate(work, obj, obj, face, d, 0.0)
                for run in range(a.first_run, a.first_run + a.runs):
                    batch = replay_specs(fr, scene=scene, run=run, seed=a.seed, object_map={obj: ref})
                    for i, s in enumerate(batch):
                        where[(name, s.run, s.seed)] = (obj, face, k, i)
                    specs += batch
    wins = {(o, f): np.zeros((len(d), len(face_rows[(o, f)]))) for o, fs in plan.items() for f, d in fs.items()}
    t = time.time()
    for row in run_rows(specs, a.workers):
        o, f, k, i = where[(str(row["object_id"]), int(row["run"]), int(row["seed"]))]
        wins[(o, f)][k, i] += row["status"] == "ok" and row["success"] == 1
    print(f"{len(specs)} experiments, {len(specs)/(time.time()-t):.2f} exp/s")
    for obj, faces in plan.items():
        arrays = {"shifts_m": np.array([0.0]), "shift_chosen": np.array(0)}
        for face, depths in faces.items():
            p = wins[(obj, face)] / a.runs
            arrays[f"{face}_depths_m"] = np.array(depths)
            arrays[f"{face}_p"] = p[None]
            arrays[f"{face}_ids"] = np.array([int(r["experiment_id"]) for r in face_rows[(obj, face)]])
            arrays[f"{face}_chosen"] = np.array(0)
            print(obj, face, " ".join(f"{d*1000:g}:{s:.2f}" for d, s in zip(depths, p.mean(1))))
        np.savez(out / f"{obj}.candidates.npz", object_id=np.array(obj), **arrays)


if __name__ == "__main__":
    main()
