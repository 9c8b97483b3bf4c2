"""Loading user meshes: format, units, sanity checks and watertight repair.

`load_mesh` turns an STL/OBJ/PLY file into a closed triangle mesh in metres
with outward normals, or raises `MeshError` with one line naming the file and
the reason.
"""

from __future__ import annotations

import io
import logging
from pathlib import Path

import numpy as np
import trimesh

from transfertwin._errors import InputError

__all__ = [
    "MAX_SIZE_M",
    "MESH_SUFFIXES",
    "MIN_SIZE_M",
    "UNITS_TO_M",
    "MeshError",
    "load_mesh",
    "parse_mesh_bytes",
    "unit_scale",
]

logger = logging.getLogger(__name__)

UNITS_TO_M: dict[str, float] = {"m": 1.0, "cm": 0.01, "mm": 0.001, "in": 0.0254}
"""Length of one file unit in metres."""

MESH_SUFFIXES = (".stl", ".obj", ".ply")
"""Accepted mesh file suffixes (case-insensitive)."""

MIN_SIZE_M = 0.01
"""Smallest accepted largest AABB extent (m)."""

MAX_SIZE_M = 2.0
"""Largest accepted largest AABB extent (m)."""

_MIN_FILL_RATIO = 1e-6  # volume / (largest extent)^3 below this: no enclosed volume


class MeshError(InputError):
    """A mesh file that cannot be used: unreadable, corrupt, empty, wrong size or open."""


def unit_scale(units: str) -> float:
    """Metres per file unit.

    Args:
        units: One of ``"m"``, ``"cm"``, ``"mm"``, ``"in"``.

    Returns:
        The scale factor to metres.

    Raises:
        InputError: For any other unit.
    """
    if units not in UNITS_TO_M:
        raise InputError(f"unknown units {units!r}: expected one of {', '.join(UNITS_TO_M)}")
    return UNITS_TO_M[units]


def load_mesh(path: str | Path, units: str = "m") -> trimesh.Trimesh:
    """Load a closed triangle mesh from an STL, OBJ or PLY file, in metres.

    Checks, in order: suffix, file exists and is readable, it parses, it has
    faces, all vertices are finite, its largest AABB extent (after unit
    conversion) is within [`MIN_SIZE_M`, `MAX_SIZE_M`], and it is a closed
    volume, after a repair (merge vertices, drop degenerate and duplicate
    faces, fill simple holes, fix winding and normals) if needed.

    Args:
        path: Mesh file; the format follows the suffix.
        units: Units of the file's coordinates (``"m"``, ``"cm"``, ``"mm"``, ``"in"``).

    Returns:
        A watertight mesh with consistent winding and positive volume (outward
        normals), vertices in metres, in the file's frame.

    Raises:
        InputError: If ``units`` is unknown.
        MeshError: If any check fails; the message names the file and the reason.
    """
    path = Path(path)
    scale = unit_scale(units)
    suffix = path.suffix.lower()
    if suffix not in MESH_SUFFIXES:
        raise MeshError(
            f"{path}: unsupported mesh format {suffix or '(none)'!r}: expected .stl, .obj or .ply"
        )
    if not path.is_file():
        raise MeshError(f"{path}: no such file")
    try:
        data = path.read_bytes()
    except OSError as exc:
        raise MeshError(f"{path}: cannot read file ({exc.strerror or exc})") from exc
    mesh = parse_mesh_bytes(data, suffix[1:], str(path))
    mesh.apply_scale(scale)
    _check_size(mesh, str(path), units)
    return _closed_volume(mesh, str(path))


def parse_mesh_bytes(data: bytes, file_type: str, name: str) -> trimesh.Trimesh:
    """Parse mesh file content and check that it has finite faces.

    Args:
        data: File content.
        file_type: ``"stl"``, ``"obj"`` or ``"ply"``.
        name: File name for error messages.

    Returns:
        The mesh, vertices merged, in file units.

    Raises:
        MeshError: If the content is corrupt, empty or has non-finite vertices.
    """
    if file_type == "stl":
        _check_stl_size(data, name)
    try:
        mesh = trimesh.load_mesh(io.BytesIO(data), file_type=file_type, process=False)
    except Exception as exc:  # parsers raise many types on corrupt input
        raise MeshError(
            f"{name}: cannot parse {file_type.upper()} file ({type(exc).__name__})"
        ) from exc
    if not isinstance(mesh, trimesh.Trimesh) or len(mesh.faces) == 0:
        raise MeshError(f"{name}: mesh is empty (no faces)")
    if not np.isfinite(mesh.vertices).all():
        raise MeshError(f"{name}: mesh has non-finite (NaN or inf) vertex coordinates")
    return mesh.process()


def _check_stl_size(data: bytes, name: str) -> None:
    """Reject STL content that is neither a size-consistent binary STL nor ASCII STL."""
    if len(data) >= 84:
        count = int(np.frombuffer(data[80:84], dtype="<u4")[0])
        if len(data) == 84 + 50 * count:
            return  # binary STL
    if data.lstrip()[:5].lower() == b"solid":
        return  # ASCII STL: the parser judges the rest
    raise MeshError(f"{name}: corrupt STL file ({len(data)} bytes, neither binary nor ASCII STL)")


def _check_size(mesh: trimesh.Trimesh, name: str, units: str) -> None:
    """Reject meshes whose largest extent is outside [MIN_SIZE_M, MAX_SIZE_M]."""
    size = float(np.max(mesh.extents))
    if not MIN_SIZE_M <= size <= MAX_SIZE_M:
        raise MeshError(
            f"{name}: largest extent {size:.4g} m (units={units!r}) is outside "
            f"{MIN_SIZE_M}..{MAX_SIZE_M} m; check the units"
        )


def _closed_volume(mesh: trimesh.Trimesh, name: str) -> trimesh.Trimesh:
    """Repair if needed and return a watertight mesh with positive volume."""
    if not (mesh.is_watertight and mesh.is_winding_consistent):
        logger.info("%s: mesh is open or inconsistently wound; repairing", name)
        mesh.merge_vertices(merge_tex=True, merge_norm=True)
        mesh.update_faces(mesh.nondegenerate_faces() & mesh.unique_faces())
        mesh.remove_unreferenced_vertices()
        trimesh.repair.fill_holes(mesh)
        trimesh.repair.fix_winding(mesh)
    if not (mesh.is_watertight and mesh.is_winding_consistent):
        raise MeshError(
            f"{name}: mesh is not a closed volume (open or non-manifold) and repair failed"
        )
    with np.errstate(invalid="ignore", divide="ignore"):  # zero volume -> NaN centre
        trimesh.repair.fix_inversion(mesh, multibody=True)
        volume = float(mesh.volume)
    if not volume > _MIN_FILL_RATIO * float(np.max(mesh.extents)) ** 3:
        raise MeshError(f"{name}: mesh encloses no volume ({volume:.3g} m^3)")
    return mesh
