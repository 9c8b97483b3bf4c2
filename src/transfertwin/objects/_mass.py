"""Rigid-body mass properties of a closed mesh of uniform density."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import trimesh

from transfertwin._errors import InputError

__all__ = [
    "DEFAULT_DENSITY_KG_M3",
    "AxialSplit",
    "MassProperties",
    "axial_mass_split",
    "mass_properties",
]

DEFAULT_DENSITY_KG_M3 = 3500.0
"""Effective density of a starter-motor core (kg/m^3).

A starter is steel, copper and an aluminium housing with air inside; 3500 kg/m^3
over its closed outer surface gives the 2–5 kg of passenger-car starters. Used
when neither a density nor a mass is given.
"""


@dataclass(frozen=True, eq=False)
class MassProperties:
    """Mass, centre of mass and inertia of a rigid body.

    Attributes:
        mass_kg: Mass in kg (> 0).
        com_m: Centre of mass in the mesh frame, shape (3,), metres (read-only).
        inertia_kg_m2: Inertia tensor about the centre of mass, axes of the mesh
            frame, shape (3, 3), kg m^2, symmetric positive definite (read-only).
    """

    mass_kg: float
    com_m: np.ndarray
    inertia_kg_m2: np.ndarray

    def __post_init__(self) -> None:
        com = np.array(self.com_m, dtype=np.float64).reshape(3)
        inertia = np.array(self.inertia_kg_m2, dtype=np.float64).reshape(3, 3)
        com.setflags(write=False)
        inertia.setflags(write=False)
        object.__setattr__(self, "mass_kg", float(self.mass_kg))
        object.__setattr__(self, "com_m", com)
        object.__setattr__(self, "inertia_kg_m2", inertia)


def mass_properties(
    mesh: trimesh.Trimesh,
    *,
    density_kg_m3: float | None = None,
    mass_kg: float | None = None,
) -> MassProperties:
    """Mass properties of a closed mesh with uniform density.

    Give at most one of ``density_kg_m3`` and ``mass_kg``; with neither,
    `DEFAULT_DENSITY_KG_M3` is used.

    Args:
        mesh: Watertight mesh with outward normals, vertices in metres.
        density_kg_m3: Uniform density in kg/m^3 (> 0).
        mass_kg: Total mass in kg (> 0); the density is mass / volume.

    Returns:
        Mass, centre of mass (mesh frame) and inertia about the centre of mass.

    Raises:
        InputError: If both or non-positive/non-finite values are given, or the
            mesh is not a closed volume with positive volume.
    """
    if density_kg_m3 is not None and mass_kg is not None:
        raise InputError("give either density_kg_m3 or mass_kg, not both")
    for name, value in (("density_kg_m3", density_kg_m3), ("mass_kg", mass_kg)):
        if value is not None and not (
            isinstance(value, (int, float)) and math.isfinite(value) and value > 0
        ):
            raise InputError(f"{name} must be a finite number > 0, got {value!r}")
    if not mesh.is_watertight:
        raise InputError("mass properties need a watertight mesh")
    unit = trimesh.triangles.mass_properties(mesh.triangles, density=1.0)
    volume = float(unit["volume"])
    if not volume > 0.0:
        raise InputError(f"mass properties need a mesh with positive volume, got {volume:.3g} m^3")
    if mass_kg is not None:
        density = float(mass_kg) / volume
    else:
        density = float(DEFAULT_DENSITY_KG_M3 if density_kg_m3 is None else density_kg_m3)
    return MassProperties(
        mass_kg=density * volume,
        com_m=np.asarray(unit["center_mass"], dtype=np.float64),
        inertia_kg_m2=density * np.asarray(unit["inertia"], dtype=np.float64),
    )


@dataclass(frozen=True, eq=False)
class AxialSplit:
    """A body of two uniform densities split at a plane across its x axis.

    Attributes:
        mass: Mass properties of the two-density body (mesh frame).
        cut_x_m: Where the plane x = const cuts the body (its uniform centre of mass).
        front_fraction: Share of the mass in front of the cut (+x, the pinion end).
        uniform_front_fraction: That share at uniform density (the front part's volume share).
    """

    mass: MassProperties
    cut_x_m: float
    front_fraction: float
    uniform_front_fraction: float


def axial_mass_split(mesh: trimesh.Trimesh, mass_kg: float, com_shift_m: float) -> AxialSplit:
    """Mass properties of `mesh` with its centre of mass moved `com_shift_m` along x.

    The mesh is cut by the plane through its uniform-density centre of mass across x into a
    rear part (x < cut, for a core: the motor end) and a front part (the drive end); each gets
    a uniform density, chosen so that the total mass stays `mass_kg` and the centre of mass
    moves by `com_shift_m` along x (+: towards +x). The inertia is the two parts' exact
    inertia about the new centre of mass (parallel-axis theorem), so the tensor stays
    consistent with the shifted mass. A shift of 0 is the uniform body.

    Raises:
        InputError: If the mesh is not watertight, or the shift would need a density <= 0 in
            either part (it must lie strictly between the two parts' centroids).
    """
    from manifold3d import Manifold, Mesh

    if not (math.isfinite(com_shift_m) and math.isfinite(mass_kg) and mass_kg > 0):
        raise InputError(f"bad mass split: mass {mass_kg!r} kg, shift {com_shift_m!r} m")
    if not mesh.is_watertight:
        raise InputError("mass properties need a watertight mesh")
    solid = Manifold(Mesh(vert_properties=np.asarray(mesh.vertices, dtype=np.float32),
                          tri_verts=np.asarray(mesh.faces, dtype=np.uint32)))  # fmt: skip
    cut = float(trimesh.triangles.mass_properties(mesh.triangles, density=1.0)["center_mass"][0])
    front, rear = solid.split_by_plane((1.0, 0.0, 0.0), cut)
    parts = []
    for part in (rear, front):
        m = part.to_mesh()
        tris = np.asarray(m.vert_properties, dtype=np.float64)[:, :3][np.asarray(m.tri_verts)]
        parts.append(trimesh.triangles.mass_properties(tris, density=1.0))
    volumes = np.array([float(p["volume"]) for p in parts])
    centres = np.array([np.asarray(p["center_mass"], dtype=np.float64) for p in parts])
    if not (volumes > 0).all():
        raise InputError("the mass split needs volume on both sides of the centre of mass")
    x_rear, x_front = centres[:, 0]
    # m_r + m_f = M and m_r x_r + m_f x_f = M (x_uniform + shift), x_uniform = cut
    m_front = mass_kg * (cut + com_shift_m - x_rear) / (x_front - x_rear)
    masses = np.array([mass_kg - m_front, m_front])
    if not (masses > 0).all():
        lo, hi = (x_rear - cut) * 1000, (x_front - cut) * 1000
        raise InputError(
            f"a centre-of-mass shift of {com_shift_m * 1000:g} mm is outside what two positive "
            f"densities can give for this body ({lo:.0f} .. {hi:.0f} mm)"
        )
    com = (masses[:, None] * centres).sum(axis=0) / mass_kg
    inertia = np.zeros((3, 3))
    for p, mass, c in zip(parts, masses, centres, strict=True):
        d = c - com
        density = mass / float(p["volume"])
        inertia += density * np.asarray(p["inertia"], dtype=np.float64)
        inertia += mass * (float(d @ d) * np.eye(3) - np.outer(d, d))
    return AxialSplit(
        MassProperties(mass_kg, com, inertia), cut,
        float(m_front / mass_kg), float(volumes[1] / volumes.sum()),
    )  # fmt: skip
