"""Average candidate sets of disjoint runs: average_runs.py OUT A_DIRS... -- B_DIRS... (equal R each)."""
import sys, numpy as np
from pathlib import Path
sys.path.insert(0, str(Path(__file__).parent))
from twin_cv import load_merged
from transfertwin.data import calibration_csv_path
from transfertwin.store import read_results
out = Path(sys.argv[1]); out.mkdir(parents=True, exist_ok=True)
cut = sys.argv.index("--")
A, B = sys.argv[2:cut], sys.argv[cut + 1:]
rows = read_results(calibration_csv_path())
ids = np.array([int(r["experiment_id"]) for r in rows])
ca, cb = load_merged(A, rows), load_merged(B, rows)
for obj in ca:
    arrays = {"shifts_m": np.array([0.0]), "shift_chosen": np.array(0)}
    for face in ca[obj].faces:
        da, db = ca[obj].depths_m[face], cb[obj].depths_m[face]
        assert np.allclose(da, db), (obj, face, da, db)
        m = ca[obj].masks[face]
        p = 0.5 * (ca[obj].faces[face][0][:, m] + cb[obj].faces[face][0][:, m])
        arrays[f"{face}_depths_m"] = da
        arrays[f"{face}_p"] = p[None]
        arrays[f"{face}_ids"] = ids[m]
        arrays[f"{face}_chosen"] = np.array(0)
    np.savez(out / f"{obj}.candidates.npz", object_id=np.array(obj), **arrays)
print("wrote", out)
