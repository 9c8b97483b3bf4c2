"""The mismatch plant's jointed parts and sagging belts, written into a scene's `MjSpec`.

`VirtualTransferSystem` builds one rigid object body and flat, rigid belt decks; the
mismatch plant (`transfertwin.plant._mismatch`) edits that spec before it is compiled:

- each `JointedPart` leaves the object body for a child body of its own at the part's root,
  on a hinge or ball joint with the part's stiffness, damping, rest angle (`springref`) and
  armature; its hull geom keeps every contact setting, and its mass is taken out of the
  core's (the object's mass stays);
- each sagging belt's deck is replaced by `SAG_SEGMENTS` slats along a half-sine sag
  profile, each tilted along its chord, a body on a vertical slide joint with a spring and
  gravity compensated (only the load presses it down). The first slat keeps the deck's
  name (the units' belt drives find it by name), the others are ``{deck}_slat{i}``.
"""

from __future__ import annotations

import math

import mujoco
import numpy as np

from transfertwin.plant._mismatch import SAG_BELTS, SAG_SEGMENTS, JointedPart
from transfertwin.sim import OBJECT_BODY, TU_BODY, belt_geom, object_hull

__all__: list[str] = []  # private to transfertwin.plant

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
