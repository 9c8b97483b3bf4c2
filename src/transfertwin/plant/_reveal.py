"""The plant's hidden truth, revealed for scoring a rehearsal after the fact.

A rehearsal is the one place where a twin's calibration can be checked against the truth:
`reveal_truth(seed, objects)` draws the hidden values of plant `seed` (as the plant does,
`transfertwin.plant._truth`) and returns the ones a calibration tries to recover — per
object the depth of each face's feature and its mass and centre of mass, for the scene μ
and the gap — as a frozen record. Only code above the twin reads it: the rehearsal's
report, given the seed from ``plant.secret``. The twin's packages (`transfertwin.study`
and below) cannot import this package (`tests/unit/test_layering.py`).

A 'mismatch' plant holds more than this (knobs, dents, a loose strip, a compliant part,
sagging belts, another contact model: `transfertwin.plant._mismatch`); its record lists
the parts present, which no proxy of the twin's class can represent, and its centre of
mass includes the mismatch's shift.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from transfertwin._errors import InputError
from transfertwin.objects import builtin_ids
from transfertwin.plant._mismatch import (
    MISMATCH_PARTS,
    PLANT_KINDS,
    draw_mismatch_scene,
    without_parts,
)
from transfertwin.plant._plant import _hidden_body, _mismatch_object
from transfertwin.plant._truth import draw_object, draw_scene

__all__ = ["HiddenObject", "HiddenScene", "PlantTruth", "reveal_truth"]


@dataclass(frozen=True)
class HiddenObject:
    """One plant object's hidden values that object calibration fits.

    Attributes:
        object_id: The core.
        depth_mm: Depth of each face's feature, ``(('front', d), ('back', d))``, mm; 0 is
            a plain face.
        feature_at: Where each face's feature sits, as fractions of the face's extent in
            x and y (``(('front', (fx, fy)), …)``; the twin's proxy puts it at 0.5).
        mass_kg: True mass.
        com_mm: True centre of mass in F_O, mm.
        contact_ms: The features' contact time constant (compliance), ms.
    """

    object_id: str
    depth_mm: tuple[tuple[str, float], ...]
    feature_at: tuple[tuple[str, tuple[float, float]], ...]
    mass_kg: float
    com_mm: tuple[float, float, float]
    contact_ms: float

    def depth_of(self, face: str) -> float:
        """The feature depth of `face`, mm."""
        return dict(self.depth_mm)[face]


@dataclass(frozen=True)
class HiddenScene:
    """The plant scene's hidden values: friction μ, gap (mm), belt-speed error (%),
    placement noise (mm, degrees) and the share of outcomes flipped by chance."""

    mu: float
    gap_mm: float
    belt_speed_error_pct: float
    placement_sigma_mm: float
    placement_sigma_deg: float
    flip_share: float


@dataclass(frozen=True)
class PlantTruth:
    """What plant `seed` hides: its scene, its objects, and the structural parts a
    'mismatch' plant adds (empty for 'in-class' and 'bullet')."""

    kind: str
    scene: HiddenScene
    objects: tuple[HiddenObject, ...]
    structural_parts: tuple[str, ...] = ()

    def object(self, object_id: str) -> HiddenObject:
        """The hidden values of `object_id` (KeyError if not revealed)."""
        for obj in self.objects:
            if obj.object_id == object_id:
                return obj
        raise KeyError(object_id)


def _hidden_object(seed: int, object_id: str, kind: str, off: frozenset[str]) -> HiddenObject:
    obj = draw_object(seed, object_id)
    _, mass_kg, com_m, _ = _hidden_body(obj)
    com = np.asarray(com_m, dtype=float)
    if kind == "mismatch":
        m, _ = without_parts(_mismatch_object(seed, object_id), draw_mismatch_scene(seed), off)
        com = com + np.asarray(m.com_shift_m)
    return HiddenObject(
        object_id,
        tuple((p.face, round(p.depth_m * 1000.0, 2)) for p in obj.protrusions),
        tuple((p.face, (p.x_frac, p.y_frac)) for p in obj.protrusions),
        round(float(mass_kg), 4),
        tuple(round(float(v) * 1000.0, 2) for v in com),  # type: ignore[arg-type]
        round(obj.feature_solref[0] * 1000.0, 1),
    )


def reveal_truth(
    seed: int, object_ids: Sequence[str], *, kind: str = "in-class",
    mismatch_off: Sequence[str] = (),
) -> PlantTruth:  # fmt: skip
    """The hidden truth of plant `seed` for `object_ids` (module docstring).

    Args:
        seed: The plant seed (``plant.secret``).
        object_ids: Built-in cores to reveal.
        kind: The plant kind (`PLANT_KINDS`).
        mismatch_off: Mismatch parts switched off (a 'mismatch' plant only).

    Raises:
        InputError: On a bad seed, kind or object.
    """
    if isinstance(seed, bool) or not isinstance(seed, int) or seed < 0:
        raise InputError(f"the plant seed must be a non-negative integer, got {seed!r}")
    if kind not in PLANT_KINDS:
        raise InputError(f"plant kind must be one of {', '.join(PLANT_KINDS)}, got {kind!r}")
    bad = sorted(set(object_ids) - set(builtin_ids()))
    if bad:
        raise InputError(f"the plant has no object {', '.join(bad)} (it holds o1..o37)")
    s = draw_scene(seed)
    scene = HiddenScene(
        round(s.mu, 4), round(s.gap_m * 1000.0, 2), round((s.belt_speed_scale - 1) * 100, 2),
        round(s.sigma_xy_m * 1000.0, 2), round(s.sigma_theta_deg, 2), round(s.flip_p, 4),
    )  # fmt: skip
    parts = tuple(p for p in MISMATCH_PARTS if p not in mismatch_off) if kind == "mismatch" else ()
    off = frozenset(mismatch_off)
    objects = tuple(_hidden_object(seed, o, kind, off) for o in object_ids)
    return PlantTruth(kind, scene, objects, parts)
