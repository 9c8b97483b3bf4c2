"""Average candidate sets of disjoint runs with equal R each (same depths, same rows):
average_equal_runs.py OUT DIR [DIR ...] — e.g. three R = 2 replays into one R = 6 set."""
import sys
from pathlib import Path

import numpy as np

out = Path(sys.argv[1])
out.mkdir(exist_ok=True)
dirs = sys.argv[2:]
for f in sorted(Path(dirs[0]).glob("*.candidates.npz")):
    zs = [np.load(Path(d) / f.name) for d in dirs]
    arrays = {k: zs[0][k] for k in zs[0].files}
    for k in zs[0].files:
        if k.endswith("_p"):
            face = k[: -len("_p")]
            for z in zs[1:]:
                assert np.array_equal(z[f"{face}_depths_m"], zs[0][f"{face}_depths_m"]), f
                assert np.array_equal(z[f"{face}_ids"], zs[0][f"{face}_ids"]), f
            arrays[k] = sum(z[k] for z in zs) / len(zs)
    np.savez(out / f.name, **arrays)
print(f"averaged {len(dirs)} sets into {out}")
