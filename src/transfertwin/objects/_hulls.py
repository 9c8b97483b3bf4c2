"""Convex decomposition (CoACD) of a mesh into hulls, cached on disk by content hash.

CoACD's output differs from run to run, so a studied mesh must always get the
same hulls: the first decomposition is stored as ``<sha256>.npz`` in the cache
directory and reused afterwards. The key covers the mesh's vertices and faces
(exact bytes) and the CoACD parameters. Files are written atomically and the
first writer wins, so processes that decompose the same mesh at the same time
all end up with the hulls of the file on disk.
"""

from __future__ import annotations

import hashlib
import io
import json
import logging
import math
import os
import zipfile
from collections.abc import Sequence
from pathlib import Path

import numpy as np
import trimesh
from scipy.spatial import ConvexHull, QhullError

from transfertwin._atomic import write_bytes_exclusive
from transfertwin._errors import InputError

__all__ = [
    "CACHE_ENV_VAR",
    "coacd_hulls",
    "coacd_params",
    "decompose_hulls",
    "default_cache_dir",
    "hull_cache_key",
    "hulls_from_npz_bytes",
    "hulls_to_npz_bytes",
    "merge_hulls",
]

logger = logging.getLogger(__name__)

CACHE_ENV_VAR = "TRANSFERTWIN_CACHE"
"""Environment variable naming the cache root; hulls go to ``$TRANSFERTWIN_CACHE/hulls``."""

_KEY_VERSION = b"transfertwin-hulls-v1"
_MIN_HULL_VOLUME_M3 = 1e-9  # 1 mm^3: smaller pieces are dropped (no effect on contacts)


def default_cache_dir() -> Path:
    """Hull cache directory: ``$TRANSFERTWIN_CACHE/hulls`` or ``~/.cache/transfertwin/hulls``."""
    root = os.environ.get(CACHE_ENV_VAR)
    base = Path(root).expanduser() if root else Path.home() / ".cache" / "transfertwin"
    return base / "hulls"


def coacd_params(threshold: float, max_hulls: int, seed: int) -> dict:
    """CoACD keyword arguments used by `decompose_hulls` (also the cache-key parameters).

    Args:
        threshold: Concavity threshold in (0, 1]; smaller gives more, tighter hulls.
        max_hulls: Upper bound on the number of hulls (>= 1).
        seed: CoACD's random seed (>= 0).

    Returns:
        Keyword arguments for `coacd.run_coacd`.

    Raises:
        InputError: If a value is out of range.
    """
    if not (
        isinstance(threshold, (int, float)) and math.isfinite(threshold) and 0 < threshold <= 1
    ):
        raise InputError(f"threshold must be in (0, 1], got {threshold!r}")
    if isinstance(max_hulls, bool) or not isinstance(max_hulls, int) or max_hulls < 1:
        raise InputError(f"max_hulls must be an integer >= 1, got {max_hulls!r}")
    if isinstance(seed, bool) or not isinstance(seed, int) or seed < 0:
        raise InputError(f"seed must be an integer >= 0, got {seed!r}")
    return {
        "threshold": float(threshold),
        "max_convex_hull": int(max_hulls),
        "seed": int(seed),
        "preprocess_mode": "auto",
        "resolution": 2000,
        "mcts_iterations": 150,
        "merge": True,
    }


def hull_cache_key(mesh: trimesh.Trimesh, params: dict) -> str:
    """SHA-256 (hex) of the mesh's exact vertices and faces and the CoACD parameters."""
    digest = hashlib.sha256(_KEY_VERSION)
    digest.update(np.ascontiguousarray(mesh.vertices, dtype="<f8").tobytes())
    digest.update(np.ascontiguousarray(mesh.faces, dtype="<i8").tobytes())
    digest.update(json.dumps(params, sort_keys=True).encode())
    return digest.hexdigest()


def decompose_hulls(
    mesh: trimesh.Trimesh,
    *,
    cache_dir: Path | None = None,
    threshold: float = 0.05,
    max_hulls: int = 24,
    seed: int = 0,
) -> tuple[np.ndarray, ...]:
    """Approximate convex decomposition of a closed mesh, cached on disk.

    Args:
        mesh: Watertight mesh, vertices in metres.
        cache_dir: Cache directory (created if missing); default `default_cache_dir`.
        threshold: CoACD concavity threshold in (0, 1].
        max_hulls: Upper bound on the number of hulls.
        seed: CoACD random seed.

    Returns:
        One read-only float64 array of shape (k_i, 3) per convex hull: the
        hull's vertices in metres, in the mesh frame.

    Raises:
        InputError: If a parameter is out of range.
    """
    params = coacd_params(threshold, max_hulls, seed)
    directory = Path(cache_dir) if cache_dir is not None else default_cache_dir()
    path = directory / f"{hull_cache_key(mesh, params)}.npz"
    if path.is_file():
        try:
            return hulls_from_npz_bytes(path.read_bytes())
        except (OSError, ValueError, KeyError, zipfile.BadZipFile) as exc:
            logger.warning("replacing unreadable hull cache file %s (%s)", path, exc)
            path.unlink(missing_ok=True)
    hulls = coacd_hulls(mesh, params)
    try:
        directory.mkdir(parents=True, exist_ok=True)
        if not write_bytes_exclusive(path, hulls_to_npz_bytes(hulls, params)):
            # another process decomposed the same mesh first: use its hulls, so
            # that every user of this mesh gets the same ones
            return hulls_from_npz_bytes(path.read_bytes())
    except (OSError, ValueError, KeyError, zipfile.BadZipFile) as exc:
        logger.warning("hull cache file %s not usable (%s)", path, exc)
    return hulls


def hulls_to_npz_bytes(hulls: Sequence[np.ndarray], meta: dict) -> bytes:
    """Encode hulls as a compressed ``.npz``: arrays ``hull_000``, … and a JSON string ``meta``."""
    arrays = {f"hull_{i:03d}": np.asarray(h, dtype="<f8") for i, h in enumerate(hulls)}
    arrays["meta"] = np.array(json.dumps(meta, sort_keys=True))
    buffer = io.BytesIO()
    np.savez_compressed(buffer, **arrays)
    return buffer.getvalue()


def hulls_from_npz_bytes(data: bytes) -> tuple[np.ndarray, ...]:
    """Decode hulls written by `hulls_to_npz_bytes`.

    Raises:
        ValueError: If the content holds no hull or a hull of the wrong shape.
    """
    with np.load(io.BytesIO(data), allow_pickle=False) as npz:
        names = sorted(n for n in npz.files if n.startswith("hull_"))
        hulls = tuple(np.array(npz[n], dtype=np.float64) for n in names)
    if not hulls or any(h.ndim != 2 or h.shape[1] != 3 or len(h) < 4 for h in hulls):
        raise ValueError("hull file holds no valid (k, 3) hull arrays")
    for hull in hulls:
        hull.setflags(write=False)
    return hulls


def coacd_hulls(mesh: trimesh.Trimesh, params: dict) -> tuple[np.ndarray, ...]:
    """Run CoACD (no cache) and return the hulls' vertex arrays.

    Hulls flatter or smaller than 1 mm^3 are dropped; each hull's vertices are
    its convex-hull vertices sorted lexicographically.

    Args:
        mesh: Watertight mesh, vertices in metres.
        params: Keyword arguments for `coacd.run_coacd` (see `coacd_params`).

    Returns:
        Read-only float64 arrays of shape (k_i, 3), metres, mesh frame.
    """
    import coacd  # imported lazily: heavy, and not needed when the cache hits

    coacd.set_log_level("error")
    vertices = np.ascontiguousarray(mesh.vertices, dtype=np.float64)
    faces = np.ascontiguousarray(mesh.faces, dtype=np.int32)
    parts = coacd.run_coacd(coacd.Mesh(vertices, faces), **params)
    hulls = [h for h in (_hull_vertices(np.asarray(v)) for v, _ in parts) if h is not None]
    if not hulls:
        logger.warning("CoACD returned no usable hull; using the mesh's convex hull")
        hulls = [np.asarray(mesh.convex_hull.vertices, dtype=np.float64)]
    for hull in hulls:
        hull.setflags(write=False)
    return tuple(hulls)


def _hull_vertices(points: np.ndarray) -> np.ndarray | None:
    """Vertices of the convex hull of ``points``, sorted; None if flat or tiny."""
    try:
        hull = ConvexHull(points)
    except (QhullError, ValueError):
        return None
    if hull.volume < _MIN_HULL_VOLUME_M3:
        return None
    vertices = np.asarray(points[hull.vertices], dtype=np.float64)
    return vertices[np.lexsort(vertices.T[::-1])]


def merge_hulls(
    hulls: Sequence[np.ndarray], budget: int, keep_last: int = 0
) -> tuple[np.ndarray, ...]:
    """Merge convex hulls into at most `budget` (a hull budget per object).

    Greedy and deterministic: while too many remain, the pair whose joint convex hull adds
    the least volume (joint volume minus both volumes; overlapping pairs go first) becomes
    that joint hull. Fewer hulls make collision detection cheaper but fill the concavities
    between merged parts. The last `keep_last` hulls (features with their own contact
    parameters) are kept apart and do not count against the budget.

    Args:
        hulls: Convex hull vertex arrays, each (k, 3).
        budget: Most hulls to keep besides the last `keep_last` (>= 1).
        keep_last: How many trailing hulls stay as they are.
    """
    if budget < 1:
        raise InputError(f"hull budget must be >= 1, got {budget!r}")
    keep_last = max(0, min(keep_last, len(hulls)))
    body = [np.asarray(h, dtype=np.float64) for h in hulls[: len(hulls) - keep_last]]
    kept = tuple(hulls[len(hulls) - keep_last :])
    if len(body) <= budget:
        return tuple(hulls)

    def volume(points: np.ndarray) -> float:
        try:
            return float(ConvexHull(points).volume)
        except (QhullError, ValueError):
            return 0.0

    vols = [volume(h) for h in body]
    cost: dict[tuple[int, int], float] = {}
    for i in range(len(body)):
        for j in range(i + 1, len(body)):
            cost[i, j] = volume(np.concatenate([body[i], body[j]])) - vols[i] - vols[j]
    alive = list(range(len(body)))
    while len(alive) > budget:
        i, j = min(cost, key=lambda ij: (cost[ij], ij))
        merged = _hull_vertices(np.concatenate([body[i], body[j]]))
        body[i] = merged if merged is not None else np.concatenate([body[i], body[j]])
        vols[i] = volume(body[i])
        alive.remove(j)
        cost = {ij: c for ij, c in cost.items() if j not in ij and i not in ij}
        for k in alive:
            if k != i:
                pair = (min(i, k), max(i, k))
                cost[pair] = volume(np.concatenate([body[i], body[k]])) - vols[i] - vols[k]
    out = [body[k] for k in alive]
    for hull in out:
        hull.setflags(write=False)
    return (*out, *kept)
