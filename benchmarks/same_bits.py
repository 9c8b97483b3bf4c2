"""Same bits before and after a change: record every field of a fixed set of experiments
(every sample's pose included), then compare two recordings field by field.

48 experiments with the fast defaults and 12 with 'reference' (all four cores of the main
job, θ step 90, one docking error, seed 7). Run `record` on each code version (e.g. with
`PYTHONPATH` pointing at a checkout of the older commit), then `compare`:

    PYTHONPATH=/path/to/old/src .venv/bin/python benchmarks/same_bits.py record old.pkl
    PYTHONPATH=src .venv/bin/python benchmarks/same_bits.py record new.pkl
    .venv/bin/python benchmarks/same_bits.py compare old.pkl new.pkl

`compare` prints how many experiments are identical (floats by their exact repr, so NaN
equals NaN) and exits 1 if any differs.
"""

from __future__ import annotations

import argparse
import dataclasses
import pickle
import sys
from pathlib import Path

OBJECTS = ("o1", "o18", "o23", "o32")


def record(out: Path) -> None:
    from transfertwin.ots import experiment_states, filter_theta_step
    from transfertwin.sim import DockingError, scene_profile
    from transfertwin.study import ExperimentSpec, run_experiment

    error = DockingError.from_mm_deg(-8.55, 2.84, 1.44)
    states = filter_theta_step(experiment_states(), 90)
    rows = []
    for profile, n in (("fast", 12), ("reference", 3)):
        scene = scene_profile(profile)
        for obj in OBJECTS:
            for s in states[:n]:
                spec = ExperimentSpec(obj, s.face, s.conveyor, s.theta_deg, docking_error=error,
                                      scene=scene, seed=7, record=True)  # fmt: skip
                rows.append(repr(dataclasses.astuple(run_experiment(spec))))
    out.write_bytes(pickle.dumps(rows))
    print(f"{len(rows)} experiments recorded to {out}")


def compare(a: Path, b: Path) -> int:
    left, right = pickle.loads(a.read_bytes()), pickle.loads(b.read_bytes())
    same = sum(x == y for x, y in zip(left, right, strict=True))
    print(f"identical: {same} of {len(left)}")
    return 0 if same == len(left) else 1


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    sub = parser.add_subparsers(dest="cmd", required=True)
    sub.add_parser("record").add_argument("out", type=Path)
    cmp = sub.add_parser("compare")
    cmp.add_argument("a", type=Path)
    cmp.add_argument("b", type=Path)
    args = parser.parse_args()
    if args.cmd == "record":
        record(args.out)
    else:
        sys.exit(compare(args.a, args.b))


if __name__ == "__main__":
    main()
