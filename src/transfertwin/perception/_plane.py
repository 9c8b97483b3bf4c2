"""RANSAC plane segmentation with an explicit seed (the belt-removal step of Fig. 5.14).

Open3D's `segment_plane` runs its iterations on several threads and is not reproducible
from run to run even with `open3d.utility.random.seed` (checked with Open3D 0.20), so the
plane is found here in numpy: `iterations` random point triples drawn from a seeded
generator, the plane with most inliers within `distance_m`, refined by a least-squares fit
to its inliers. Same seed, same points → the same plane, bit for bit.
"""

from __future__ import annotations

import numpy as np

__all__ = ["fit_plane", "ransac_plane"]


def fit_plane(points: np.ndarray) -> np.ndarray:
    """Least-squares plane (a, b, c, d) with unit normal (c >= 0) through points (n, 3)."""
    centre = points.mean(axis=0)
    _, _, vt = np.linalg.svd(points - centre, full_matrices=False)
    normal = vt[2] if vt[2, 2] >= 0 else -vt[2]
    return np.append(normal, -normal @ centre)


def ransac_plane(
    points: np.ndarray, distance_m: float, iterations: int, seed: int
) -> tuple[np.ndarray, np.ndarray]:
    """The dominant plane of points (n, 3): (a, b, c, d) and its inlier mask (n,).

    Raises:
        ValueError: With fewer than 3 points.
    """
    n = len(points)
    if n < 3:
        raise ValueError("RANSAC needs at least 3 points")
    rng = np.random.default_rng(seed)
    idx = np.stack([rng.choice(n, size=3, replace=False) for _ in range(iterations)])
    p0, p1, p2 = points[idx[:, 0]], points[idx[:, 1]], points[idx[:, 2]]
    normals = np.cross(p1 - p0, p2 - p0)
    norms = np.linalg.norm(normals, axis=1)
    ok = norms > 1e-12
    normals, p0 = normals[ok] / norms[ok, None], p0[ok]
    if len(normals) == 0:
        return fit_plane(points), np.ones(n, dtype=bool)
    offsets = -np.einsum("ij,ij->i", normals, p0)
    counts = np.zeros(len(normals), dtype=np.int64)
    for start in range(0, len(normals), 64):  # bounded memory: 64 planes x n points
        dist = np.abs(points @ normals[start : start + 64].T + offsets[start : start + 64])
        counts[start : start + 64] = (dist <= distance_m).sum(axis=0)
    best = int(np.argmax(counts))
    inliers = np.abs(points @ normals[best] + offsets[best]) <= distance_m
    plane = fit_plane(points[inliers])
    return plane, np.abs(points @ plane[:3] + plane[3]) <= distance_m
