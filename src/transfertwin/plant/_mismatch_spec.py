"""The mismatch plant's jointed parts and sagging belts, written into a scene's `MjSpec`.

`VirtualTransferSystem` builds one rigid object body and flat, rigid belt decks; the
mismatch plant (`transfertwin.plant._mismatch`) edits that spec before it is compiled.
`jointed_parts` turns a `MismatchObject`'s appendage and compliant part into `JointedPart`s
(their joints' springs, damping, armature, mass and inertia), then:

- each `JointedPart` leaves the object body for a child body of its own at the part's root,
  on its hinge, slide or ball joints with the part's stiffness, damping, rest angle
  (`springref`) and armature; its hull geom keeps every contact setting, and its mass is
  taken out of the core's (the object's mass stays);
- each sagging belt's deck is replaced by `SAG_SEGMENTS` slats along a half-sine sag
  profile, each tilted along its chord, a body on a vertical slide joint with a spring and
  gravity compensated (only the load presses it down). The first slat keeps the deck's
  name (the units' belt drives find it by name), the others are ``{deck}_slat{i}``.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import mujoco
import numpy as np

from transfertwin.plant._mismatch import SAG_BELTS, SAG_SEGMENTS, MismatchObject, strip_side
from transfertwin.sim import OBJECT_BODY, TU_BODY, belt_geom, object_hull

__all__: list[str] = []  # private to transfertwin.plant

#: The plant's base physics step (s): the armatures keep the joints stable at it.
_STEP_S = 0.005
@dataclass(frozen=True)
class JointedPart:
    """A part of the plant object on a joint of its own (F_O, metres, kilograms).

    Attributes:
        hull: Index of its hull among `mismatched_hulls`' hulls.
        joint: 'hinge' (the appendage, about `axis`), 'slide' (the appendage folding
            along `axis`, by at most `fold_m`) or 'ball' (the compliant part). A second
            part on the same hull is a second joint of the same body.
        anchor: The joint's position (the part's root).
        axis: The hinge's axis (unit; unused for a ball joint).
        stiffness, damping, springref, armature: The joint's spring (N·m/rad), damping
            (N·m·s/rad), rest angle (rad; a hinge's) and rotor inertia (kg·m²).
        mass: The part's mass (taken out of the core's, so the object's stays).
        com: Its centre of mass.
        inertia: Its principal moments about its centre of mass (its bounding box's).
    """

    hull: int
    joint: str
    anchor: tuple[float, float, float]
    axis: tuple[float, float, float]
    stiffness: float
    damping: float
    springref: float
    armature: float
    mass: float
    com: tuple[float, float, float]
    inertia: tuple[float, float, float]
    fold_m: float = 0.0


#: Densities of the appendage (nylon) and of the compliant part (a plastic housing).
_NYLON, _HOUSING = 1150.0, 1500.0
#: Undamped period of a joint, in base physics steps, below which an armature slows it.
_MIN_PERIOD_STEPS = 12
#: Least effective mass of a jointed part at its far end (kg), by its joint's armature.
_MIN_TIP_KG = 0.05


def _part(hull: int, joint: str, verts: np.ndarray, anchor: np.ndarray, axis: np.ndarray,
          stiffness: float, ratio: float, springref: float,
          density: float) -> JointedPart:  # fmt: skip
    from scipy.spatial import ConvexHull

    mass = density * float(ConvexHull(verts).volume)
    com = verts.mean(axis=0)
    ext = np.ptp(verts, axis=0)
    inertia = mass / 12 * np.array([ext[1] ** 2 + ext[2] ** 2, ext[0] ** 2 + ext[2] ** 2,
                                    ext[0] ** 2 + ext[1] ** 2])  # fmt: skip
    arm = com - anchor
    if joint == "hinge":  # about the axis through the anchor
        i_joint = float(axis**2 @ inertia) + mass * float(arm @ arm - (arm @ axis) ** 2)
    elif joint == "slide":
        i_joint = mass
    else:
        i_joint = float(inertia.mean()) + mass * float(arm @ arm)
    # At its far end a part moves as at least _MIN_TIP_KG would: MuJoCo's soft contacts
    # scale their stiffness by the effective mass, and a 0.4 g strip is pushed centimetres
    # into a belt by its own weak spring.
    reach2 = 1.0 if joint == "slide" else float(np.max(np.sum((verts - anchor) ** 2, axis=1)))
    armature = max(0.0, stiffness * (_MIN_PERIOD_STEPS * _STEP_S / (2 * math.pi)) ** 2 - i_joint,
                   _MIN_TIP_KG * reach2 - i_joint)  # fmt: skip
    damping = ratio * 2 * math.sqrt(stiffness * (i_joint + armature))
    return JointedPart(hull, joint, tuple(float(v) for v in anchor),  # type: ignore[arg-type]
                       tuple(float(v) for v in axis), stiffness, damping, springref, armature,  # type: ignore[arg-type]
                       mass, tuple(float(v) for v in com), tuple(float(v) for v in inertia))  # type: ignore[arg-type]  # fmt: skip


def jointed_parts(m: MismatchObject, hulls: tuple[np.ndarray, ...], in_class_hulls: int,
                  in_class_features: int) -> tuple[JointedPart, ...]:  # fmt: skip
    """The parts of `m` on joints of their own, over `hulls` = `mismatched_hulls`' hulls of
    an in-class object of `in_class_hulls` hulls, the last `in_class_features` features."""
    parts = []
    if m.appendage is not None and m.appendage_joint is not None:
        a = np.asarray(m.appendage, dtype=float)
        d = a[3:6]
        side = strip_side(d)
        k, ratio, ref = m.appendage_joint
        verts = np.asarray(hulls[-1], dtype=float)
        # A strip bends about its width axis; about its thickness axis (w/t)² times stiffer.
        parts.append(_part(len(hulls) - 1, "hinge", verts, a[:3], side, k, ratio, ref, _NYLON))
        parts.append(_part(len(hulls) - 1, "hinge", verts, a[:3], np.cross(side, d),
                           k * (a[7] / a[8]) ** 2, ratio, 0.0, _NYLON))  # fmt: skip
        # Pushed along its length it buckles and folds flat (a load no hinge can take):
        # a weak spring along it, down to its whole length.
        fold = _part(len(hulls) - 1, "slide", verts, a[:3], d, 10 * k / a[6] ** 2, ratio, 0.0,
                     _NYLON)  # fmt: skip
        parts.append(dataclasses.replace(fold, fold_m=a[6]))
    if m.compliant is not None:
        core = in_class_hulls - in_class_features
        k_in = int(m.compliant[0])
        idx = k_in if k_in < core else k_in + len(m.bumps)  # the knobs follow the core
        k, ratio = m.compliant[4], m.compliant[5]
        parts.append(_part(idx, "ball", np.asarray(hulls[idx], dtype=float),
                           np.asarray(m.compliant[1:4]), np.zeros(3), k, ratio, 0.0,
                           _HOUSING))  # fmt: skip
    return tuple(parts)


#: Moving mass of one slat (kg): a stretch of belt and its slider bed.
_SLAT_KG = 0.5

_CONTACT = ("condim", "friction", "solref", "solimp", "priority", "contype", "conaffinity",
            "rgba", "surfacevel")  # fmt: skip


def slat_name(unit: str, belt: str, i: int) -> str:
    """The geom name of slat `i` of a sagging belt (slat 0 keeps the deck's name)."""
    deck = belt_geom(unit, belt, "deck")
    return deck if i == 0 else f"{deck}_slat{i}"


def _settings(geom: mujoco.MjsGeom) -> dict[str, object]:
    return {k: np.copy(getattr(geom, k)) if isinstance(getattr(geom, k), np.ndarray)
            else getattr(geom, k) for k in _CONTACT}  # fmt: skip


def add_jointed_parts(spec: mujoco.MjSpec, parts: tuple[JointedPart, ...]) -> None:
    """Move each part's hull geom into a body of its own on the part's joint."""
    core = spec.body(OBJECT_BODY)
    degrees = bool(spec.compiler.degree)
    names: list[str] = []
    bodies: dict[int, mujoco.MjsBody] = {}
    for n, part in enumerate(parts):
        if part.hull in bodies:  # another joint of the same part (same anchor)
            _add_joint(bodies[part.hull], f"{OBJECT_BODY}_part{n}_joint", part, degrees)
            continue
        old = spec.geom(object_hull(part.hull))
        settings, mesh = _settings(old), old.meshname
        spec.delete(old)
        anchor = np.asarray(part.anchor)
        body = core.add_body(name=f"{OBJECT_BODY}_part{n}", pos=anchor)
        body.explicitinertial = True
        body.mass = part.mass
        body.ipos = np.asarray(part.com) - anchor
        body.inertia = np.asarray(part.inertia)
        bodies[part.hull] = body
        _add_joint(body, f"{OBJECT_BODY}_part{n}_joint", part, degrees)
        geom = body.add_geom(name=object_hull(part.hull), type=mujoco.mjtGeom.mjGEOM_MESH,
                             meshname=mesh, pos=-anchor)  # fmt: skip
        for key, value in settings.items():
            setattr(geom, key, value)
        geom.mass = 0.0
        core.mass = core.mass - part.mass
        names.append(body.name)
    for i, a in enumerate(names):  # parts may touch each other only through the core
        for b in names[i + 1 :]:
            spec.add_exclude(bodyname1=a, bodyname2=b)


def _add_joint(body: mujoco.MjsBody, name: str, part: JointedPart, degrees: bool) -> None:
    kind = getattr(mujoco.mjtJoint, f"mjJNT_{part.joint.upper()}")
    axis = np.asarray(part.axis) if part.joint != "ball" else np.array([0.0, 0.0, 1.0])
    joint = body.add_joint(name=name, type=kind, axis=axis)
    if part.fold_m:
        joint.limited = mujoco.mjtLimited.mjLIMITED_TRUE
        joint.range = np.array([-part.fold_m, 0.0])
    joint.stiffness = np.array([part.stiffness, 0.0, 0.0])
    joint.damping = np.array([part.damping, 0.0, 0.0])
    # MjSpec reads a hinge's angles in the compiler's unit (degrees by default)
    degree = part.joint == "hinge" and degrees
    joint.springref = math.degrees(part.springref) if degree else part.springref
    joint.armature = part.armature


def add_sagging_decks(spec: mujoco.MjSpec, sag: tuple[tuple[float, float, float], ...]) -> None:
    """Replace each belt's deck by slats on springs along its sag profile (`SAG_BELTS`
    order: depth at mid-span, stiffness per slat, damping ratio)."""
    for (unit, belt), (depth, stiffness, ratio) in zip(SAG_BELTS, sag, strict=True):
        deck = spec.geom(belt_geom(unit, belt, "deck"))
        settings = _settings(deck)
        pos, size = np.asarray(deck.pos, dtype=float), np.asarray(deck.size, dtype=float)
        parent = deck.parent
        spec.delete(deck)
        x0, x1 = pos[0] - size[0], pos[0] + size[0]
        xs = np.linspace(x0, x1, SAG_SEGMENTS + 1)
        zs = -depth * np.sin(np.pi * (xs - x0) / (x1 - x0))  # the belt's top surface
        bodies = []
        for i in range(SAG_SEGMENTS):
            dx, dz = xs[i + 1] - xs[i], zs[i + 1] - zs[i]
            phi = -math.atan2(dz, dx)  # about y: the slat's x along its chord
            quat = np.array([math.cos(phi / 2), 0.0, math.sin(phi / 2), 0.0])
            top = np.array([0.5 * (xs[i] + xs[i + 1]), pos[1], 0.5 * (zs[i] + zs[i + 1])])
            body = parent.add_body(name=f"{slat_name(unit, belt, i)}_body", pos=top)
            body.gravcomp = 1.0
            body.explicitinertial = True
            body.mass = _SLAT_KG
            body.inertia = np.full(3, 1e-3)
            joint = body.add_joint(name=f"{slat_name(unit, belt, i)}_joint",
                                   type=mujoco.mjtJoint.mjJNT_SLIDE, axis=[0, 0, 1])  # fmt: skip
            joint.stiffness = np.array([stiffness, 0.0, 0.0])
            joint.damping = np.array([ratio * 2 * math.sqrt(stiffness * _SLAT_KG), 0.0, 0.0])
            # The slat's top face through `top`, overlapping its neighbours by 1 mm (below
            # their surface: the profile only ever bends upwards).
            normal = np.array([math.sin(phi), 0.0, math.cos(phi)])
            geom = body.add_geom(name=slat_name(unit, belt, i), type=mujoco.mjtGeom.mjGEOM_BOX,
                                 size=[0.5 * math.hypot(dx, dz) + 0.001, size[1], size[2]],
                                 pos=-size[2] * normal, quat=quat)  # fmt: skip
            for key, value in settings.items():
                setattr(geom, key, value)
            geom.mass = 0.0
            bodies.append(body.name)
        others = ["world"] + ([TU_BODY] if unit == "tu" else [])
        for i, name in enumerate(bodies):  # slats touch only the object
            for other in others + bodies[i + 1 :]:
                spec.add_exclude(bodyname1=other, bodyname2=name)
