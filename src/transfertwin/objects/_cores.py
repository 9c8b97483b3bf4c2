"""Procedural starter-motor cores as meshes in the object frame F_O.

Pipeline (deterministic, so the shipped STL files can be regenerated bit for
bit): spec -> CSG solid (manifold3d) -> shift the origin to the centre of
mass -> float32 vertices in a canonical order -> binary STL bytes -> parsed
back exactly as a shipped file is parsed.

Object frame F_O: +x towards the pinion, +y away from the solenoid, +z up when
lying on face 'front'; origin at the centre of mass (uniform density).
"""

from __future__ import annotations

import numpy as np
import trimesh

from transfertwin.objects._core_builder import build_core_solid
from transfertwin.objects._core_draw import core_spec
from transfertwin.objects._mesh import parse_mesh_bytes
from transfertwin.objects._stl import stl_bytes

__all__ = ["core_stl_bytes", "generate_core", "mesh_from_stl_bytes"]


def core_stl_bytes(index: int) -> bytes:
    """Binary STL (metres, frame F_O) of procedural core ``index``.

    Args:
        index: Core number >= 1 (1..37 are the built-in cores).

    Returns:
        The STL file content; identical for identical ``index``.

    Raises:
        InputError: If ``index`` is not an integer >= 1.
    """
    solid = build_core_solid(core_spec(index))
    raw = solid.to_mesh64()
    vertices = np.asarray(raw.vert_properties, dtype=np.float64)[:, :3]
    faces = np.asarray(raw.tri_verts, dtype=np.int64)
    mesh = trimesh.Trimesh(vertices, faces, process=False)
    vertices = (vertices - mesh.center_mass).astype(np.float32).astype(np.float64)
    return stl_bytes(_canonical(vertices, faces))


def generate_core(index: int) -> trimesh.Trimesh:
    """Procedural, deterministic, watertight mesh of core ``index`` in F_O (metres).

    Equal to the mesh of the shipped ``o<index>.stl`` for 1 <= index <= 37.

    Args:
        index: Core number >= 1.

    Returns:
        The mesh; on face 'front' its lowest points (can and solenoid) lie on
        the resting plane.

    Raises:
        InputError: If ``index`` is not an integer >= 1.
    """
    return mesh_from_stl_bytes(core_stl_bytes(index), f"core {index}")


def mesh_from_stl_bytes(data: bytes, name: str) -> trimesh.Trimesh:
    """Parse STL content the way shipped core files are parsed (vertices merged)."""
    return parse_mesh_bytes(data, "stl", name)


def _canonical(vertices: np.ndarray, faces: np.ndarray) -> trimesh.Trimesh:
    """Mesh with vertices sorted lexicographically and faces in a canonical order.

    Each face is rotated (keeping its winding) to start at its smallest vertex
    index, then faces are sorted; the result does not depend on the order in
    which the CSG kernel emitted vertices and triangles.
    """
    order = np.lexsort(vertices.T[::-1])
    rank = np.empty_like(order)
    rank[order] = np.arange(len(order))
    faces = rank[faces]
    shift = np.argmin(faces, axis=1)
    rows = np.arange(len(faces))[:, None]
    faces = faces[rows, (shift[:, None] + np.arange(3)) % 3]
    faces = faces[np.lexsort(faces.T[::-1])]
    return trimesh.Trimesh(vertices[order], faces, process=False)
