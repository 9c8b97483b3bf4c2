"""Binary STL writer with repeatable bytes, and the content hash of a mesh.

trimesh's own exporter is not used for package data because its header and
normals may change between versions; here the bytes depend only on the
vertices and faces: an 80-byte fixed header, the face count, and per face the
unit normal, the three vertices (little-endian float32) and a zero attribute.
"""

from __future__ import annotations

import hashlib
from pathlib import Path

import numpy as np
import trimesh

from transfertwin._atomic import write_bytes_atomic

__all__ = ["mesh_content_hash", "stl_bytes", "write_stl"]

_HEADER = b"transfertwin binary STL, units: metres".ljust(80, b" ")
_RECORD = np.dtype([("normal", "<f4", (3,)), ("vertices", "<f4", (3, 3)), ("attr", "<u2")])


def stl_bytes(mesh: trimesh.Trimesh) -> bytes:
    """Encode a mesh as binary STL.

    Args:
        mesh: Triangle mesh, vertices in metres.

    Returns:
        The file content: 84 + 50 × n_faces bytes.
    """
    triangles = np.asarray(mesh.vertices, dtype=np.float64)[np.asarray(mesh.faces)]
    triangles = triangles.astype(np.float32).astype(np.float64)
    normals = np.cross(triangles[:, 1] - triangles[:, 0], triangles[:, 2] - triangles[:, 0])
    lengths = np.linalg.norm(normals, axis=1, keepdims=True)
    normals = np.divide(normals, lengths, out=np.zeros_like(normals), where=lengths > 0.0)
    records = np.zeros(len(triangles), dtype=_RECORD)
    records["normal"] = normals
    records["vertices"] = triangles
    count = np.array([len(triangles)], dtype="<u4")
    return _HEADER + count.tobytes() + records.tobytes()


def write_stl(mesh: trimesh.Trimesh, path: Path) -> None:
    """Write ``mesh`` as binary STL to ``path`` atomically (see `stl_bytes`)."""
    write_bytes_atomic(path, stl_bytes(mesh))


def mesh_content_hash(mesh: trimesh.Trimesh) -> str:
    """SHA-256 (hex) of a mesh's vertices (float64) and faces (int64), in their order.

    Args:
        mesh: Triangle mesh.

    Returns:
        64 hex digits; equal meshes (same arrays) give equal hashes.
    """
    digest = hashlib.sha256()
    digest.update(np.ascontiguousarray(mesh.vertices, dtype="<f8").tobytes())
    digest.update(np.ascontiguousarray(mesh.faces, dtype="<i8").tobytes())
    return digest.hexdigest()
