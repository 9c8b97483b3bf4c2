"""Rigid-body mass properties of a closed mesh of uniform density."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import trimesh

from transfertwin._errors import InputError

__all__ = ["DEFAULT_DENSITY_KG_M3", "MassProperties", "mass_properties"]

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
