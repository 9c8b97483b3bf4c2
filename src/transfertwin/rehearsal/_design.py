"""Which plant experiments a rehearsal runs: the study's random calibration design (and the
held-out test experiments from their own stream), or a space-filling one (a Latin hypercube
over face and θ per object), and the stratified split of the calibration rows into training
and held-out rows.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import numpy as np

from transfertwin._errors import InputError
from transfertwin.ots import FACES, THETA_SINGLE
from transfertwin.plant import PlantRequest

__all__ = ["DESIGNS", "calibration_design", "holdout_split"]

#: Calibration designs: the study's random states, or space-filling ones.
DESIGNS = ("random", "space-filling")


#: Random streams of the designs: calibration experiments and held-out test experiments.
_DESIGN_TAGS = {"calibration": 0x44455349, "test": 0x54455354}


def calibration_design(
    objects: Sequence[str], k: int, seed: int, purpose: str = "calibration",
    design: str = "random",
) -> list[PlantRequest]:  # fmt: skip
    """K pre-transfer states, objects in turn, the conveyor 'both' where θ allows it
    (Eq. 6.5), else left or right. 'random' (the study's calibration design): face and θ
    uniform. 'space-filling': per object, its n states a Latin hypercube sample over (face,
    θ) (`scipy.stats.qmc.LatinHypercube`: each of n equal θ strata and each face's half of
    the face axis hit once, so an object's few tries spread over both faces and the whole
    circle instead of clumping). `purpose` 'test' draws the held-out test experiments from
    their own stream."""
    if design not in DESIGNS:
        raise InputError(f"design must be one of {', '.join(DESIGNS)}, got {design!r}")
    rng = np.random.default_rng([seed, _DESIGN_TAGS[purpose]])
    single = set(THETA_SINGLE)
    n = len(objects)
    lhs = None
    if design == "space-filling":
        from scipy.stats import qmc

        lhs = {j: qmc.LatinHypercube(d=2, rng=rng).random((k - j + n - 1) // n)
               for j in range(min(n, k))}  # fmt: skip
    out = []
    for i in range(k):
        if lhs is None:  # (the draws in the order the study's design has always made them)
            face = FACES[int(rng.integers(len(FACES)))]
            theta = int(rng.integers(-179, 181))
        else:
            u_face, u_theta = lhs[i % n][i // n]
            face, theta = FACES[int(u_face * len(FACES))], -179 + int(u_theta * 360)
        conveyor = ("left", "right")[int(rng.integers(2))] if theta in single else "both"
        out.append(PlantRequest(objects[i % n], face, conveyor, theta))
    return out


def holdout_split(
    rows: Sequence[Mapping[str, object]], fraction: float, seed: int
) -> tuple[list[Mapping[str, object]], list[Mapping[str, object]]]:
    """(training rows, held-out rows): per object, a `fraction` of its rows held out."""
    rng = np.random.default_rng([seed, 0x484F4C44])
    test_idx: set[int] = set()
    by_object: dict[str, list[int]] = {}
    for i, r in enumerate(rows):
        by_object.setdefault(str(r["object_id"]), []).append(i)
    n_test = round(len(rows) * fraction)
    quota = {o: len(ix) / len(rows) * n_test for o, ix in by_object.items()}
    for o, ix in by_object.items():
        take = min(len(ix) - 1, max(1, round(quota[o]))) if len(ix) > 1 else 0
        test_idx.update(int(j) for j in rng.choice(ix, size=take, replace=False))
    train = [r for i, r in enumerate(rows) if i not in test_idx]
    test = [r for i, r in enumerate(rows) if i in test_idx]
    return train, test
