"""Calibrated proxy objects: a base object plus features below a face's resting plane.

A real starter-motor core rests on flange ears, bolt heads and terminal studs that can drop
into the gap between the docked belts and catch on the transfer unit's pulley. The built-in
procedural cores keep such features inside the can's radius, so nothing hangs below their
contact line. A proxy adds, per face, one `Protrusion`: a convex box whose bottom lies
`depth_m` below that face's resting plane. It is appended to the base object's convex hulls
(no CoACD run, deterministic); the protrusions add no mass.

A proxy may also move the centre of mass along the object's x axis (`ProxySpec.com_shift_m`):
a real core's motor end (steel can, armature, field) and drive end (aluminium housing, pinion)
differ in density. The body is then two bodies of uniform density, cut across x at its
uniform centre of mass (`transfertwin.objects.axial_mass_split`): same mass, centre of mass
moved by the shift, inertia of the two parts about it. 0, the family prior, is the uniform
body.

**A proxy is not a scan.** `transfertwin calibrate object` infers the protrusion depths and the
centre-of-mass shift of one real object from its real outcomes; the result reproduces how often
the object catches in the gap, not its true shape or mass distribution. A proxy is saved as a
small JSON file (suffix `.proxy.json`) that `load_object` — and so every command that takes a
mesh — accepts; files without `com_shift_m` (written before it existed) load as uniform.
"""

from __future__ import annotations

import dataclasses
import json
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from transfertwin._errors import InputError
from transfertwin.objects._mass import AxialSplit, MassProperties, axial_mass_split
from transfertwin.objects._model import ObjectModel

__all__ = [
    "MAX_COM_SHIFT_M",
    "PROXY_SUFFIX",
    "Protrusion",
    "ProxySpec",
    "mass_split",
    "proxy_model",
    "read_proxy",
    "write_proxy",
]

#: File suffix of a saved proxy object.
PROXY_SUFFIX = ".proxy.json"

#: Largest centre-of-mass shift a proxy may have (m).
MAX_COM_SHIFT_M = 0.05


@dataclass(frozen=True)
class Protrusion:
    """A box below the resting plane of one face (F_O, metres).

    Attributes:
        face: 'front' (below the lowest hull point in F_O) or 'back' (above the highest,
            which is the bottom once the object is turned over).
        depth_m: How far the box's bottom lies below the face's resting plane (0: none).
        x_frac: Axial centre as a fraction of the AABB's x range (0 rear, 1 pinion).
        y_frac: Lateral centre as a fraction of the AABB's y range.
        size_x_m: Extent along the object's x axis.
        size_y_m: Extent along its y axis.
        height_m: Extent from its bottom up into the body (None: depth + 15 mm).
    """

    face: str
    depth_m: float
    x_frac: float = 0.5
    y_frac: float = 0.5
    size_x_m: float = 0.006
    size_y_m: float = 0.03
    height_m: float | None = None

    def __post_init__(self) -> None:
        if self.face not in ("front", "back"):
            raise InputError(f"protrusion face must be 'front' or 'back', got {self.face!r}")
        if not (0.0 <= self.depth_m <= 0.1):
            raise InputError(f"protrusion depth must be in 0..0.1 m, got {self.depth_m!r}")
        if not (0.0 <= self.x_frac <= 1.0 and 0.0 <= self.y_frac <= 1.0):
            raise InputError("protrusion x_frac and y_frac must be in 0..1")

    def hull(self, model: ObjectModel) -> np.ndarray:
        """The 8 vertices (F_O) of this protrusion on `model`, (8, 3)."""
        verts = np.vstack(model.hulls)
        lo, hi = verts.min(axis=0), verts.max(axis=0)
        cx = lo[0] + self.x_frac * (hi[0] - lo[0])
        cy = lo[1] + self.y_frac * (hi[1] - lo[1])
        height = self.depth_m + 0.015 if self.height_m is None else self.height_m
        if self.face == "front":
            z0 = lo[2] - self.depth_m
            z1 = z0 + height
        else:
            z1 = hi[2] + self.depth_m
            z0 = z1 - height
        hx, hy = self.size_x_m / 2, self.size_y_m / 2
        return np.array(
            [[x, y, z] for x in (cx - hx, cx + hx) for y in (cy - hy, cy + hy) for z in (z0, z1)]
        )


@dataclass(frozen=True)
class ProxySpec:
    """A calibrated proxy: its id, base object reference, protrusions and mass distribution.

    Attributes:
        com_shift_m: Shift of the centre of mass along the object's x axis (+: towards the
            pinion), as two densities split across x (`axial_mass_split`); 0 (the family
            prior) keeps the base's mass properties. A nonzero shift replaces the base's mass
            distribution (it starts from the base mesh at uniform density, same mass).
        mass_kg, com_m: *Measured* mass properties (a scale and a balance: a real core's mass
            is not spread uniformly over its shape). Set, they replace the mass and centre of
            mass (F_O, m); the inertia is scaled with the mass. A measured centre of mass and a
            calibrated shift exclude each other.
    """

    object_id: str
    base: str
    protrusions: tuple[Protrusion, ...]
    note: str = "calibrated proxy, not a scan"
    com_shift_m: float = 0.0
    mass_kg: float | None = None
    com_m: tuple[float, float, float] | None = None

    def __post_init__(self) -> None:
        shift = self.com_shift_m
        if not (isinstance(shift, (int, float)) and abs(shift) <= MAX_COM_SHIFT_M):
            raise InputError(
                f"com_shift_m must be within ±{MAX_COM_SHIFT_M * 1000:g} mm, got {shift!r}"
            )
        object.__setattr__(self, "com_shift_m", float(shift))
        if self.mass_kg is not None and not (0 < self.mass_kg < 1000):
            raise InputError(f"proxy mass must be in (0, 1000) kg, got {self.mass_kg!r}")
        if self.com_m is not None:
            com = tuple(float(v) for v in self.com_m)
            if len(com) != 3 or not all(abs(v) < 1.0 for v in com):
                raise InputError(f"proxy com_m must be 3 coordinates within 1 m, got {com!r}")
            if self.com_shift_m != 0:
                raise InputError("a proxy has either a measured com_m or a com_shift_m, not both")
            object.__setattr__(self, "com_m", com)

    def to_dict(self) -> dict[str, object]:
        """JSON-ready description (measured mass fields only when measured)."""
        prots = [dataclasses.asdict(p) for p in self.protrusions]
        out: dict[str, object] = {
            "object_id": self.object_id, "base": self.base, "note": self.note, "protrusions": prots,
            "com_shift_m": self.com_shift_m,
        }  # fmt: skip
        if self.mass_kg is not None:
            out["mass_kg"] = self.mass_kg
        if self.com_m is not None:
            out["com_m"] = list(self.com_m)
        return out


def mass_split(base: ObjectModel, spec: ProxySpec) -> AxialSplit:
    """The two-density body of `spec`'s centre-of-mass shift on `base` (mass kept)."""
    return axial_mass_split(base.mesh, base.mass.mass_kg, spec.com_shift_m)


def proxy_model(base: ObjectModel, spec: ProxySpec) -> ObjectModel:
    """`base` with one extra box hull per protrusion of positive depth; for a nonzero
    `com_shift_m`, the two-density mass properties of `mass_split`; and the measured mass
    properties of `spec` where it has them."""
    extra = tuple(p.hull(base) for p in spec.protrusions if p.depth_m > 0)
    mass = base.mass if spec.com_shift_m == 0 else mass_split(base, spec).mass
    if spec.mass_kg is not None or spec.com_m is not None:
        kg = mass.mass_kg if spec.mass_kg is None else spec.mass_kg
        com = mass.com_m if spec.com_m is None else np.asarray(spec.com_m, dtype=float)
        mass = MassProperties(kg, com, np.asarray(mass.inertia_kg_m2) * (kg / mass.mass_kg))
    return dataclasses.replace(
        base, object_id=spec.object_id, hulls=tuple(base.hulls) + extra, mass=mass,
        source=f"proxy of {base.source}", spec=None,
        feature_hulls=base.feature_hulls + len(extra),
    )  # fmt: skip


def write_proxy(spec: ProxySpec, path: str | Path) -> Path:
    """Save `spec` as JSON (`path` must end in `.proxy.json`)."""
    from transfertwin._atomic import write_atomic

    path = Path(path)
    if not path.name.endswith(PROXY_SUFFIX):
        raise InputError(f"{path}: a proxy file must end in {PROXY_SUFFIX}")
    return write_atomic(path, json.dumps(spec.to_dict(), indent=2) + "\n")


def read_proxy(path: str | Path) -> ProxySpec:
    """Read a proxy saved by `write_proxy`; InputError on anything malformed."""
    try:
        desc = json.loads(Path(path).read_text())
        prots = tuple(Protrusion(**p) for p in desc["protrusions"])
        com = desc.get("com_m")
        return ProxySpec(str(desc["object_id"]), str(desc["base"]), prots,
                         str(desc.get("note", "")),
                         float(desc.get("com_shift_m", 0.0)), mass_kg=desc.get("mass_kg"),
                         com_m=None if com is None else tuple(com))  # fmt: skip
    except OSError as exc:
        raise InputError(f"{path}: cannot read: {exc.strerror}") from None
    except (ValueError, KeyError, TypeError) as exc:
        raise InputError(f"{path}: not a proxy object file ({exc})") from None
