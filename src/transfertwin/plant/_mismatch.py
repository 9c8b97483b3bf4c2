"""Structural mismatch: a plant the twin's model class cannot represent exactly.

The in-class plant (`EmulatedPlant(seed)`, kind 'in-class') differs from the twin only in
values of the twin's own family: one box protrusion per face, a centre-of-mass offset, μ,
gap, a belt-speed factor, compliant features. A *mismatch* plant (`kind='mismatch'`) is the
in-class plant of the same seed plus differences in structure, drawn from their own random
streams (so the in-class draws do not move):

- **bumps anywhere on the mesh**: 2–5 small convex knobs (cubes of 3–8 mm edge, randomly
  turned) at random outer vertices of the core, pushed 0–3 mm out along the direction from
  its centre — not a box under a face's centre, and any may meet a belt or the gap's edge;
- **dents**: on 1–3 hulls of the core, the vertices within 8–15 mm of one of its vertices
  pulled 1–3 mm towards the hull's centroid (MuJoCo collides the convex hull of what
  remains: a flattened patch);
- **a loose cable-tie-like appendage** (with probability 0.6): a thin strip 2 × 5 ×
  25–45 mm from a random outer vertex, pointing outwards within 50°, a body of its own at
  its root on two hinges and a slide (it bends as a thin strip does): about its width axis
  a bending stiffness of 2e-4–2e-3 N·m/rad with a set (the spring's rest angle, MuJoCo
  `springref`) of ±0.15 rad, about its thickness axis (width/thickness)² = 6.25 times
  stiffer, and along its length a weak spring down to its whole length (pushed end-on it
  buckles and folds flat); damping ratio 0.05–0.5; nylon, about 0.4 g;
- **a compliant part** (with probability 0.8): one of the in-class features (a face's
  protrusion: a clip, a cable housing), or without one the core hull farthest from the
  core's centre, a body of its own on a ball joint at its root (where it meets the core):
  rotational stiffness 0.5–5 N·m/rad, damping ratio 0.2–1, 1500 kg/m³ — it gives way when
  it meets the gap's edge or a pulley, which no contact softness of a rigid body does;
- **non-uniform mass in 3-D**: the inertia scaled per axis of F_O by 0.8–1.25 (mass
  moved away from or towards each axis, which no centre-of-mass shift along x represents)
  and the centre of mass moved by up to ±12, ±6, ±6 mm on top of the in-class offset;
- **belts**: speed ripple from pulley run-out, ±2–8 % at each pulley's revolution
  frequency with a random phase per unit, and each unit's right belt off its left by up to
  ±3 % (the twin's belts are equal and steady);
- **belt sag and compliance**: each belt's deck between its pulleys is `SAG_SEGMENTS`
  slats following a sag profile, 0.5–3 mm deep at mid-span (a half sine, none at the
  pulleys), each slat a body on a vertical slide joint with a spring (1e4–6e4 N/m per slat,
  damping ratio 0.5–1, weightless: gravity compensated) so that the load presses it down
  (a 4 kg core about 0.5–2 mm more); the twin's deck is one flat rigid box;
- **contact model and solver**: MuJoCo's PGS solver with a pyramidal friction cone,
  condim 4 (torsional friction), impratio 1.5–5 and a softer, wider impedance (solimp
  width 2–5 mm), against the twin's Newton solver, elliptic cone, condim 3, impratio 1.
  Unlike the other parts this one is not structural: every one of these is a setting of
  the twin's own `PhysicsConfig` (solver, cone, condim, impratio, solimp), which the twin
  could search but its rehearsal does not (it tunes μ and the gap). It is a mismatch in
  the calibration's space, not outside the model class.

The jointed parts are stiff or light against the plant's 5 ms step: each joint carries an
armature (rotor inertia) that keeps its undamped period at least 12 steps and makes its
part move, at its far end, as at least 50 g would (MuJoCo's soft contacts scale their
stiffness by the effective mass: a bare 0.4 g strip is pushed centimetres into a belt by
its own spring). So a strip bends back in a few tenths of a second rather than at once.
The plant's pose readout (a camera) follows the core body and sees the jointed parts where
they were drawn; their mass is taken out of the core's.

A second physics engine is a plant kind of its own, 'bullet' (`transfertwin.plant._bullet`:
the in-class plant in PyBullet), not a part of this mismatch.
"""

from __future__ import annotations

import dataclasses
import math
import zlib
from dataclasses import dataclass

import numpy as np

from transfertwin._errors import InputError
from transfertwin.plant._truth import PLANT_TAG

__all__: list[str] = []  # private to transfertwin.plant

#: Plant kinds: today's plant of the twin's own model class, the structural mismatch, and
#: the in-class plant's hidden object and scene simulated in another engine, PyBullet
#: (`transfertwin.plant._bullet`: the engine itself is the structural difference).
PLANT_KINDS = ("in-class", "mismatch", "bullet")

#: Parts of the mismatch that can be switched off one by one (ablation, benchmark):
#: shape (knobs, dents), mass (inertia, centre of mass), belts (ripple, skew), contact
#: (solver and contact model), appendage (the loose strip on its joints), compliant (the
#: elastic part on its ball joint), sag (sagging, compliant belt decks).
MISMATCH_PARTS = ("shape", "mass", "belts", "contact", "appendage", "compliant", "sag")


def check_mismatch_off(parts: tuple[str, ...], kind: str) -> frozenset[str]:
    """The mismatch parts to switch off, as a set; InputError unless each is one of
    `MISMATCH_PARTS` and the plant is a mismatch plant (none is always allowed)."""
    if sorted(set(parts) - set(MISMATCH_PARTS)) or (parts and kind != "mismatch"):
        raise InputError(f"mismatch parts to switch off: {', '.join(MISMATCH_PARTS)} "
                         f"(on a mismatch plant), got {', '.join(parts)}")  # fmt: skip
    return frozenset(parts)

#: Slats per belt deck of a sagging belt.
SAG_SEGMENTS = 4

#: The belts of a sagging plant, in the order of `MismatchScene.sag`: (unit, belt).
SAG_BELTS = (("tm", "left"), ("tm", "right"), ("tu", "left"), ("tu", "right"))


@dataclass(frozen=True)
class MismatchObject:
    """Structural differences of one plant object (F_O, metres).

    Attributes:
        bumps: Per knob: centre (x, y, z), edge length, rotation quaternion (w, x, y, z).
        dents: Per dent: hull index, centre (x, y, z), radius, depth.
        appendage: Root (x, y, z), unit direction (x, y, z), length, width, thickness; or
            None.
        inertia_scale: Factors of the inertia tensor's diagonal in F_O (x, y, z).
        com_shift_m: Centre-of-mass shift on top of the in-class offset.
        appendage_joint: The appendage's hinge: stiffness (N·m/rad), damping ratio, rest
            angle (rad, `springref`); None without an appendage.
        compliant: The compliant part: index of its hull among the in-class object's hulls,
            its root (x, y, z), rotational stiffness (N·m/rad), damping ratio; or None.
    """

    bumps: tuple[tuple[float, ...], ...]
    dents: tuple[tuple[float, ...], ...]
    appendage: tuple[float, ...] | None
    inertia_scale: tuple[float, float, float]
    com_shift_m: tuple[float, float, float]
    appendage_joint: tuple[float, float, float] | None = None
    compliant: tuple[float, ...] | None = None


@dataclass(frozen=True)
class MismatchScene:
    """Structural differences of the plant's scene: belt ripple and skew, contact model,
    belt sag and compliance (`sag`: per belt of `SAG_BELTS`, its depth at mid-span (m), each
    slat's spring stiffness (N/m) and damping ratio; empty: flat rigid decks)."""

    ripple: float
    ripple_phase: tuple[float, float]
    right_belt_skew: tuple[float, float]
    impratio: float
    solimp_width_m: float
    contact: bool = True  # False: the twin's contact model and solver (an ablation)
    sag: tuple[tuple[float, float, float], ...] = ()


def _rng(seed: int, *key: int) -> np.random.Generator:
    return np.random.default_rng([PLANT_TAG, seed, *key])


def _unit(v: np.ndarray) -> np.ndarray:
    n = float(np.linalg.norm(v))
    return v / n if n > 0 else np.array([0.0, 0.0, 1.0])


def draw_mismatch_object(seed: int, object_id: str, hulls: tuple[np.ndarray, ...],
                         core_hulls: int) -> MismatchObject:  # fmt: skip
    """The structural differences of plant object `object_id` (seeded by the plant seed
    and the id); `hulls` are the in-class object's hulls, the first `core_hulls` the core's
    own (not its features)."""
    rng = _rng(seed, 6, zlib.crc32(object_id.encode()))
    verts = np.concatenate([np.asarray(h, dtype=float) for h in hulls[:core_hulls]])
    centre = verts.mean(axis=0)
    outer = verts[np.linalg.norm(verts - centre, axis=1) > 0]
    bumps = []
    for _ in range(int(rng.integers(2, 6))):
        v = outer[int(rng.integers(len(outer)))]
        out = _unit(v - centre) * float(rng.uniform(0.0, 0.003))
        q = _unit(rng.normal(size=4))
        bumps.append((*(float(c) for c in v + out), float(rng.uniform(0.003, 0.008)),
                      *(float(c) for c in q)))  # fmt: skip
    dents = []
    for h in rng.choice(core_hulls, size=min(core_hulls, int(rng.integers(1, 4))), replace=False):
        hv = np.asarray(hulls[int(h)], dtype=float)
        c = hv[int(rng.integers(len(hv)))]
        dents.append((float(h), *(float(x) for x in c), float(rng.uniform(0.008, 0.015)),
                      float(rng.uniform(0.001, 0.003))))  # fmt: skip
    appendage = None
    if rng.random() < 0.6:
        root = outer[int(rng.integers(len(outer)))]
        d = _unit(_unit(root - centre) + math.tan(math.radians(50)) * rng.uniform(-1, 1, 3) / 2)
        appendage = (*(float(c) for c in root), *(float(c) for c in d),
                     float(rng.uniform(0.025, 0.045)), 0.005, 0.002)  # fmt: skip
    scale = tuple(float(v) for v in rng.uniform(0.8, 1.25, 3))
    shift = (float(rng.uniform(-0.012, 0.012)), float(rng.uniform(-0.006, 0.006)),
             float(rng.uniform(-0.006, 0.006)))  # fmt: skip
    # The joints draw from a stream of their own: the draws above stay as they were.
    jrng = _rng(seed, 8, zlib.crc32(object_id.encode()))
    hinge = (float(10 ** jrng.uniform(math.log10(2e-4), math.log10(2e-3))),
             float(jrng.uniform(0.05, 0.5)), float(jrng.uniform(-0.15, 0.15)))  # fmt: skip
    compliant = None
    features = len(hulls) - core_hulls
    if jrng.random() < 0.8 and (features or core_hulls > 1):
        if features:
            k = core_hulls + int(jrng.integers(features))
        else:  # the core hull farthest out: a lug, a flap
            cents = [np.asarray(h, dtype=float).mean(axis=0) for h in hulls[:core_hulls]]
            k = int(np.argmax([np.linalg.norm(c - centre) for c in cents]))
        hv = np.asarray(hulls[k], dtype=float)
        c = hv.mean(axis=0)
        u = _unit(centre - c)
        root = c + u * float(np.max((hv - c) @ u))  # where the part meets the core
        compliant = (float(k), *(float(x) for x in root),
                     float(10 ** jrng.uniform(math.log10(0.5), math.log10(5.0))),
                     float(jrng.uniform(0.2, 1.0)))  # fmt: skip
    return MismatchObject(tuple(bumps), tuple(dents), appendage, scale, shift,  # type: ignore[arg-type]
                          hinge if appendage is not None else None, compliant)  # fmt: skip


def without_parts(obj: MismatchObject, scene: MismatchScene,
                  off: frozenset[str]) -> tuple[MismatchObject, MismatchScene]:  # fmt: skip
    """The mismatch with the parts in `off` (of `MISMATCH_PARTS`) switched back to the
    in-class plant's."""
    if "shape" in off:
        obj = dataclasses.replace(obj, bumps=(), dents=(), appendage=None)
    if "mass" in off:
        obj = dataclasses.replace(obj, inertia_scale=(1.0, 1.0, 1.0), com_shift_m=(0.0, 0.0, 0.0))
    if "belts" in off:
        scene = dataclasses.replace(scene, ripple=0.0, right_belt_skew=(0.0, 0.0))
    if "contact" in off:
        scene = dataclasses.replace(scene, contact=False)
    if "appendage" in off:
        obj = dataclasses.replace(obj, appendage=None, appendage_joint=None)
    if "compliant" in off:
        obj = dataclasses.replace(obj, compliant=None)
    if "sag" in off:
        scene = dataclasses.replace(scene, sag=())
    return obj, scene


def draw_mismatch_scene(seed: int) -> MismatchScene:
    """The structural scene differences of plant `seed`."""
    rng, srng = _rng(seed, 7), _rng(seed, 9)  # the sag's own stream
    return MismatchScene(
        ripple=float(rng.uniform(0.02, 0.08)),
        ripple_phase=(float(rng.uniform(0, 2 * math.pi)), float(rng.uniform(0, 2 * math.pi))),
        right_belt_skew=(float(rng.uniform(-0.03, 0.03)), float(rng.uniform(-0.03, 0.03))),
        impratio=float(rng.uniform(1.5, 5.0)),
        solimp_width_m=float(rng.uniform(0.002, 0.005)),
        sag=tuple(
            (
                float(srng.uniform(0.0005, 0.003)),
                float(srng.uniform(1e4, 6e4)),
                float(srng.uniform(0.5, 1.0)),
            )
            for _ in SAG_BELTS
        ),
    )


def _cube(centre: np.ndarray, edge: float, quat: np.ndarray) -> np.ndarray:
    """The 8 corners (8, 3) of a cube of `edge` at `centre`, turned by unit quaternion."""
    w, x, y, z = quat
    rot = np.array([
        [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
        [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
        [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
    ])  # fmt: skip
    corners = np.array([[sx, sy, sz] for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)])
    return centre + (corners * edge / 2) @ rot.T


def strip_side(d: np.ndarray) -> np.ndarray:
    """The width axis of a strip along unit `d`: horizontal unless `d` is vertical."""
    return _unit(np.cross(d, [0.0, 0.0, 1.0]) if abs(d[2]) < 0.99 else np.cross(d, [1.0, 0, 0]))


def _strip(root: np.ndarray, d: np.ndarray, length: float, width: float,
           thick: float) -> np.ndarray:  # fmt: skip
    """The 8 corners of a strip from `root` along unit `d` (its width horizontal)."""
    side = strip_side(d)
    up = np.cross(side, d)
    return np.array([root + a * length * d + b * width / 2 * side + c * thick / 2 * up
                     for a in (0, 1) for b in (-1, 1) for c in (-1, 1)])  # fmt: skip


def mismatched_hulls(hulls: tuple[np.ndarray, ...], features: int,
                    m: MismatchObject) -> tuple[tuple[np.ndarray, ...], int]:  # fmt: skip
    """The plant object's collision hulls and how many of the last are features: the core's
    hulls dented, the knobs (rigid, part of the core), the in-class features (the last
    `features` of `hulls`), then the appendage (a feature: compliant like them)."""
    core = [np.array(h, dtype=float) for h in hulls[: len(hulls) - features]]
    for h, cx, cy, cz, radius, depth in m.dents:
        hv = core[int(h)]
        near = np.linalg.norm(hv - np.array([cx, cy, cz]), axis=1) <= radius
        inward = hv.mean(axis=0) - hv[near]
        norms = np.linalg.norm(inward, axis=1, keepdims=True)
        hv[near] = hv[near] + inward / np.maximum(norms, 1e-9) * np.minimum(depth, norms / 2)
    knobs = [_cube(np.array(b[:3]), b[3], np.array(b[4:8])) for b in m.bumps]
    feats = [np.asarray(h, dtype=float) for h in hulls[len(hulls) - features :]]
    if m.appendage is not None:
        a = m.appendage
        feats.append(_strip(np.array(a[:3]), np.array(a[3:6]), a[6], a[7], a[8]))
    return (*core, *knobs, *feats), len(feats)


def mismatched_inertia(inertia: np.ndarray, m: MismatchObject) -> np.ndarray:
    """The inertia tensor with its diagonal in F_O scaled per axis, kept a valid tensor
    (every principal moment at most the sum of the other two)."""
    s = np.sqrt(np.asarray(m.inertia_scale, dtype=float))
    out = np.asarray(inertia, dtype=float) * np.outer(s, s)
    vals, vecs = np.linalg.eigh(out)
    for _ in range(3):  # clip towards the triangle inequality
        vals = np.minimum(vals, (vals.sum() - vals) * 0.999)
    return (vecs * vals) @ vecs.T

