"""The hidden ground truth of an emulated plant, drawn from its seed.

Everything here is private to `transfertwin.plant`: the twin sees a plant only through
`EmulatedPlant.run` (requests in, outcome rows out). The priors are deliberately wider than
the twin's: the built-in cores' shipped features (calibrated on the real data) are single
protrusions of 0-26 mm under the face's centre; a plant object's feature may lie anywhere
under the face, with any depth in 0..26 mm and any size, its mass is not uniform, and its
features are compliant (a contact time constant of 30-80 ms against the body's 20 ms: cable
housings, clips and rubber yield under load).
"""

from __future__ import annotations

import functools
import math
import zlib
from dataclasses import dataclass

import numpy as np

from transfertwin.objects import Protrusion
from transfertwin.study.docking import PerStationCopula, marginal_family, read_docking_errors

__all__: list[str] = []  # private to transfertwin.plant

#: Tag mixed into every seed of the plant, so its streams never meet the twin's.
PLANT_TAG = 0x504C4E54  # "PLNT"

#: The prior of a face's hidden feature: plain with this probability, else a depth uniform
#: in FEATURE_DEPTH_M. It follows what object calibration found on the four real cores on
#: the default (prism-pulley) scene: 4 of 8 faces plain, the others 4-26 mm. With it a
#: plant's success share on random states is 0.66-0.77 over seeds 1-6 (real data: 0.67);
#: the prior it replaces (plain with 0.3, else 4-32 mm, set for 25 mm cylinder pulleys)
#: gave 0.47-0.68 (docs/explanation/rehearsal.md).
P_PLAIN_FACE = 0.5
FEATURE_DEPTH_M = (0.004, 0.026)


@dataclass(frozen=True)
class ObjectTruth:
    """One plant object: resting features, centre-of-mass offset (F_O, m), mass factor, and
    the compliance of its features (contact time constant s, damping ratio)."""

    object_id: str
    protrusions: tuple[Protrusion, ...]
    com_offset_m: tuple[float, float, float]
    mass_scale: float
    feature_solref: tuple[float, float] = (0.02, 1.0)


@dataclass(frozen=True)
class SceneTruth:
    """The plant's scene: friction, gap, belt-speed error, TU height step and pitch,
    placement noise, outcome flip probability."""

    mu: float
    gap_m: float
    belt_speed_scale: float
    step_z_m: float
    pitch_rad: float
    sigma_xy_m: float
    sigma_theta_deg: float
    flip_p: float


@dataclass(frozen=True)
class DockingTruth:
    """Per-station perturbation of the real docking-error copula: value = shift + scale * x
    per component (mm, mm, deg), station order of the fitted copula."""

    stations: tuple[str, ...]
    shift: tuple[tuple[float, float, float], ...]
    scale: tuple[tuple[float, float, float], ...]


def _rng(seed: int, *key: int) -> np.random.Generator:
    return np.random.default_rng([PLANT_TAG, seed, *key])


def draw_object(seed: int, object_id: str) -> ObjectTruth:
    """The hidden object `object_id` of plant `seed` (independent of the other objects)."""
    rng = _rng(seed, 1, zlib.crc32(object_id.encode()))
    prots = []
    for face in ("front", "back"):
        depth = 0.0 if rng.random() < P_PLAIN_FACE else float(rng.uniform(*FEATURE_DEPTH_M))
        prots.append(
            Protrusion(
                face,
                round(depth, 4),
                x_frac=round(float(rng.uniform(0.25, 0.75)), 3),
                y_frac=round(float(rng.uniform(0.35, 0.65)), 3),
                size_x_m=round(float(rng.uniform(0.004, 0.012)), 4),
                size_y_m=round(float(rng.uniform(0.02, 0.05)), 4),
            )
        )
    com = (
        float(np.clip(rng.normal(0.0, 0.004), -0.01, 0.01)),
        float(np.clip(rng.normal(0.0, 0.002), -0.005, 0.005)),
        float(np.clip(rng.normal(0.0, 0.002), -0.005, 0.005)),
    )
    scale = float(rng.uniform(0.9, 1.1))
    # Drawn last, so that the earlier draws of a plant do not depend on it.
    solref = (round(float(rng.uniform(0.03, 0.08)), 4), round(float(rng.uniform(0.5, 1.0)), 3))
    return ObjectTruth(object_id, tuple(prots), com, scale, solref)


def draw_scene(seed: int) -> SceneTruth:
    """The hidden scene of plant `seed`."""
    rng = _rng(seed, 2)
    return SceneTruth(
        mu=float(rng.uniform(0.38, 0.62)),
        gap_m=float(rng.uniform(0.009, 0.016)),
        belt_speed_scale=float(1.0 + rng.uniform(-0.05, 0.05)),
        step_z_m=float(rng.uniform(-0.003, 0.003)),
        pitch_rad=math.radians(float(rng.uniform(-1.0, 1.0))),
        sigma_xy_m=float(rng.uniform(0.002, 0.004)),
        sigma_theta_deg=float(rng.uniform(1.0, 3.0)),
        flip_p=float(rng.uniform(0.01, 0.04)),
    )


#: Marginal families of the plant's base copula: the full candidate list (`FAMILIES`) takes
#: ~20x longer to fit (student-t and gamma fits) and picks normal for 10 of 12 marginals.
FAST_FAMILIES = ("normal", "truncnorm", "kde")


@functools.lru_cache(maxsize=1)
def real_copula() -> PerStationCopula:
    """The per-station copula of the shipped real docking errors (fitted once per process)."""
    errors, units = read_docking_errors(None, need_units=True)
    return PerStationCopula.fit(errors, units, families=[marginal_family(f) for f in FAST_FAMILIES])


def draw_docking(seed: int) -> DockingTruth:
    """The hidden docking-error perturbation of plant `seed`."""
    rng = _rng(seed, 3)
    stations = real_copula().units
    shift = tuple(
        (float(rng.normal(0, 2.0)), float(rng.normal(0, 2.0)), float(rng.normal(0, 0.3)))
        for _ in stations
    )
    scale = tuple(tuple(float(v) for v in rng.lognormal(0.0, 0.15, size=3)) for _ in stations)
    return DockingTruth(stations, shift, scale)  # type: ignore[arg-type]
