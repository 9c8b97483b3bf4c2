"""`ObjectModel`: everything the simulation needs to know about one object."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import trimesh

from transfertwin.objects._core_spec import CoreSpec
from transfertwin.objects._mass import MassProperties

__all__ = ["ObjectModel"]


@dataclass(frozen=True, eq=False)
class ObjectModel:
    """A rigid object: surface mesh, collision hulls and mass properties, in F_O.

    Object frame F_O: +x towards the pinion (drive end), +y away from the
    engagement relay (solenoid), +z up when lying on face 'front'; face 'back'
    is the same object turned 180° about x. Built-in cores have their origin
    at the centre of mass; user meshes are shifted so that it is too.

    Instances may be shared (built-in models are memoised): treat ``mesh`` as
    read-only; the hull and mass arrays are read-only numpy arrays.

    Attributes:
        object_id: ``"o1"``..``"o37"`` for built-in cores, else the file stem.
        mesh: Closed surface mesh in metres, frame F_O.
        hulls: Convex hulls, one (k_i, 3) float64 vertex array each, metres, F_O.
        mass: Mass, centre of mass and inertia about it (F_O axes).
        source: ``"builtin"`` or the path of the mesh file.
        content_hash: SHA-256 (hex) of the mesh's vertices and faces.
        spec: Procedural specification of a built-in core, None for user meshes.
        feature_hulls: How many of the last `hulls` are features added by a calibrated
            proxy (its protrusions); the scene's `feature_mu` applies to those.
    """

    object_id: str
    mesh: trimesh.Trimesh
    hulls: tuple[np.ndarray, ...]
    mass: MassProperties
    source: str
    content_hash: str
    spec: CoreSpec | None = None
    feature_hulls: int = 0

    @property
    def is_builtin(self) -> bool:
        """True for the shipped cores o1..o37."""
        return self.source == "builtin"
