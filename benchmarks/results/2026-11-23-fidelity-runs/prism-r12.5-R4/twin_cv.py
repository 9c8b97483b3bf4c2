"""Twin-only CV/in-sample from candidate folders, merged per object/face by depth.

usage: twin_cv.py [--penalty P] [--keep 0,4,...] DIR [DIR ...]
(shift axis: only shift 0 is used)."""
import argparse, sys
import numpy as np
from transfertwin.data import calibration_csv_path
from transfertwin.store import read_results
from transfertwin.study.calibration._evaluate import (
    JointCandidates, fold_predictions, in_sample, cv_splits, _pooled, _mean_std, score)
from transfertwin.study.fullstate import clopper_pearson


def load_merged(dirs, rows, keep=None, exclude_dirs_for=None):
    ids = np.array([int(r["experiment_id"]) for r in rows])
    pos = {int(e): j for j, e in enumerate(ids)}
    n = len(rows)
    out = {}
    objs = sorted({r["object_id"] for r in rows}, key=lambda o: int(o[1:]))
    for obj in objs:
        per_face = {}
        for d in dirs:
            try:
                z = np.load(f"{d}/{obj}.candidates.npz")
            except FileNotFoundError:
                continue
            for face in ("front", "back"):
                if f"{face}_p" not in z:
                    continue
                p = z[f"{face}_p"]
                if p.ndim == 3:
                    p = p[0]
                depths = np.round(z[f"{face}_depths_m"] * 1000, 3)
                cols = [pos[int(e)] for e in z[f"{face}_ids"]]
                slot = per_face.setdefault(face, {"cols": cols, "d": {}})
                assert slot["cols"] == cols
                for k, dm in enumerate(depths):
                    if keep is not None and dm not in keep:
                        continue
                    if dm in slot["d"]:
                        if not np.array_equal(slot["d"][dm], p[k]):
                            print(f"WARN {obj} {face} {dm}: differs between folders", file=sys.stderr)
                    else:
                        slot["d"][dm] = p[k]
        preds, masks, dd = {}, {}, {}
        for face, slot in per_face.items():
            ds = sorted(slot["d"])
            full = np.full((1, len(ds), n), np.nan)
            for k, dm in enumerate(ds):
                full[0, k, slot["cols"]] = slot["d"][dm]
            mask = np.zeros(n, bool); mask[slot["cols"]] = True
            preds[face], masks[face], dd[face] = full, mask, np.array(ds) / 1000
        out[obj] = JointCandidates(np.array([0.0]), dd, preds, masks)
    return out


def evaluate(cands, rows, penalty, verbose=True):
    y = np.array([int(r["success"]) for r in rows])
    objects = np.array([r["object_id"] for r in rows])
    faces = np.array([r["face"] for r in rows])
    splits = cv_splits(y, 5, 5, 0)
    folded = fold_predictions(cands, objects, y, splits, penalty, 0.0)
    parts = [(t, p, thr) for t, p, thr, _ in folded]
    reps = [_pooled(parts[r * 5:(r + 1) * 5], y, len(y))[0] for r in range(5)]
    cv = _mean_std(reps)
    p_in, thr, chosen = in_sample(cands, objects, y, penalty, 0.0)
    ins = score(p_in, y, thr).to_dict()
    if verbose:
        print(f"twin CV F0.5 {cv['f05']:.3f} ± {cv['f05_std']:.3f} prec {cv['precision']:.3f} rec {cv['recall']:.3f} brier {cv['brier']:.3f}")
        print(f"twin in-sample F0.5 {ins['f05']:.3f} prec {ins['precision']:.3f} rec {ins['recall']:.3f} brier {ins['brier']:.3f}")
        desc = []
        for obj, c in chosen.items():
            desc.append(f"{obj} " + " ".join(f"{f} {cands[obj].depths_m[f][c[f]]*1000:g}mm" for f in cands[obj].faces))
        print("chosen:", "; ".join(desc))
        for obj in cands:
            m = objects == obj
            ci = clopper_pearson(int(y[m].sum()), int(m.sum()))
            sim = float(p_in[m].mean())
            raw = cands[obj].predictions(chosen[obj])[m]
            print(f"  {obj}: real {y[m].mean():.2f} [{ci.low:.2f}, {ci.high:.2f}] twin {sim:.2f} "
                  f"{'inside' if ci.low <= sim <= ci.high else 'OUTSIDE'} (raw sim {raw.mean():.2f})")
        # fold choice variability
        from collections import Counter
        var = Counter()
        for _, _, _, ch in folded:
            for obj, c in ch.items():
                for f in cands[obj].faces:
                    var[(obj, f, round(cands[obj].depths_m[f][c[f]]*1000, 1))] += 1
        print("fold choices:", dict(sorted(var.items())))
    return cv, ins


if __name__ == "__main__":
    ap = argparse.ArgumentParser()
    ap.add_argument("dirs", nargs="+")
    ap.add_argument("--penalty", type=float, default=0.02)
    ap.add_argument("--keep", default=None)
    a = ap.parse_args()
    rows = read_results(calibration_csv_path())
    keep = None if a.keep is None else {float(v) for v in a.keep.split(",")}
    evaluate(load_merged(a.dirs, rows, keep), rows, a.penalty)
