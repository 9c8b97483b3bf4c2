"""The object detector of Fig. 5.14: from raw depth frames to one AABB per object.

Steps, in the study's order:

1. invalid-point removal (pixels without depth);
2. transform into the fixed frame F_T (the camera pose of each frame; frames taken from
   several viewpoints are merged here, Sec. 5.5);
3. workspace crop (`Workspace`: own belts, plus the docked unit's);
4. voxel-grid downsampling (Open3D);
5. RANSAC plane removal: the belts (`ransac_plane`); repeated up to `max_planes` times, a
   plane counts as a belt when its normal is within `plane_max_tilt_deg` of z, its
   inliers span at least `plane_min_span_m` (one object's flat top is smaller than that)
   and lie no higher than `plane_max_z_m` on average (the belts are at z = 0 in F_T; the
   flat tops of two objects in a row can span more than `plane_min_span_m`);
6. statistical outlier removal on k nearest neighbours (Open3D);
7. Euclidean cluster extraction (Open3D's DBSCAN);
8. one AABB per cluster. Clusters whose footprints (x, y boxes) overlap are merged first:
   two objects cannot share floor space, while one object seen at a grazing angle can fall
   apart into pieces (a side face sampled row by row, a part under an overhang whose link
   to the body is hidden). Clusters with fewer than `min_cluster_points` points or whose top
   is less than `min_height_m` above the belt plane are dropped. The plane fit removed an
   object's lowest `plane_distance_m`, and objects rest on the belts: each box therefore
   extends down to the belt plane under it (a choice, docs/perception.md).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np

from transfertwin.perception._aabb import AABB
from transfertwin.perception._camera import View
from transfertwin.perception._plane import ransac_plane
from transfertwin.perception._workspace import Workspace

if TYPE_CHECKING:
    import open3d as o3d

__all__ = ["Detection", "DetectorConfig", "detect"]


@dataclass(frozen=True)
class DetectorConfig:
    """Parameters of the pipeline of Fig. 5.14 (lengths in metres)."""

    voxel_m: float = 0.004
    plane_distance_m: float = 0.004
    plane_iterations: int = 200
    max_planes: int = 3
    plane_max_tilt_deg: float = 15.0
    plane_min_span_m: float = 0.3
    plane_max_z_m: float = 0.02
    outlier_neighbours: int = 16
    outlier_std_ratio: float = 10.0
    cluster_eps_m: float = 0.03
    cluster_min_points: int = 8
    min_cluster_points: int = 30
    min_height_m: float = 0.01


@dataclass(frozen=True)
class Detection:
    """The detector's output for one set of frames.

    Attributes:
        boxes: One AABB per detected object, largest cluster first.
        points: (n, 3) the points that reached the clustering step, in F_T.
        labels: (n,) cluster index of each point into `boxes` (-1: noise or dropped).
        belt_z: Height of the belt plane(s) found (m), or an empty tuple.
        counts: Points left after each step (for docs and tuning).
    """

    boxes: tuple[AABB, ...]
    points: np.ndarray = field(repr=False)
    labels: np.ndarray = field(repr=False)
    belt_z: tuple[float, ...] = ()
    counts: dict[str, int] = field(default_factory=dict)


def _cloud(points: np.ndarray) -> o3d.geometry.PointCloud:
    import open3d as o3d  # here, not at module level: importing Open3D takes seconds, and
    # every `transfertwin cps ...` command imports this package through the transport flow

    return o3d.geometry.PointCloud(o3d.utility.Vector3dVector(np.ascontiguousarray(points)))


def _remove_planes(
    pts: np.ndarray, cfg: DetectorConfig, seed: int
) -> tuple[np.ndarray, list[np.ndarray]]:
    """Points without the belt planes, and the planes removed."""
    planes: list[np.ndarray] = []
    cos_tilt = math.cos(math.radians(cfg.plane_max_tilt_deg))
    for k in range(cfg.max_planes):
        if len(pts) < 3:
            break
        plane, inliers = ransac_plane(pts, cfg.plane_distance_m, cfg.plane_iterations, seed + k)
        span = np.ptp(pts[inliers, :2], axis=0).max() if inliers.any() else 0.0
        high = float(pts[inliers, 2].mean()) > cfg.plane_max_z_m if inliers.any() else True
        if plane[2] < cos_tilt or span < cfg.plane_min_span_m or high:
            break
        planes.append(plane)
        pts = pts[~inliers]
    return pts, planes


def _height_above(planes: list[np.ndarray], pts: np.ndarray) -> np.ndarray:
    """Height (n,) of points above the nearest-below belt plane (z above z = 0 if none)."""
    if not planes:
        return pts[:, 2].copy()
    heights = np.stack([(pts @ p[:3] + p[3]) / p[2] for p in planes])  # vertical distances
    above = np.where(heights >= -0.02, heights, np.inf)
    return above.min(axis=0)


def _merge_overlapping(pts: np.ndarray, clusters: list[np.ndarray]) -> list[np.ndarray]:
    """Union of clusters (boolean masks) whose x-y bounding boxes overlap, until none do."""
    merged = True
    while merged:
        merged = False
        boxes = [(pts[m, :2].min(axis=0), pts[m, :2].max(axis=0)) for m in clusters]
        for i in range(len(clusters)):
            for j in range(i + 1, len(clusters)):
                (lo_i, hi_i), (lo_j, hi_j) = boxes[i], boxes[j]
                if np.all(lo_i <= hi_j) and np.all(lo_j <= hi_i):
                    clusters[i] = clusters[i] | clusters.pop(j)
                    merged = True
                    break
            if merged:
                break
    return clusters


def detect(
    views: Sequence[View], workspace: Workspace, cfg: DetectorConfig | None = None, seed: int = 0
) -> Detection:
    """Run the pipeline of Fig. 5.14 on one or more frames (merged in F_T).

    Args:
        views: Frames with their camera poses.
        workspace: Where objects are expected.
        cfg: Pipeline parameters.
        seed: Seed of the RANSAC draws.
    """
    cfg = cfg if cfg is not None else DetectorConfig()
    counts: dict[str, int] = {"raw": int(sum(len(v.points_c) for v in views))}
    pts = np.concatenate([v.points_t() for v in views]) if views else np.empty((0, 3))
    counts["valid"] = len(pts)
    pts = pts[workspace.contains(pts)]
    counts["workspace"] = len(pts)
    empty = Detection((), np.empty((0, 3)), np.empty(0, dtype=int), (), counts)
    if len(pts) < 3:
        return empty
    pts = np.asarray(_cloud(pts).voxel_down_sample(cfg.voxel_m).points)
    counts["voxel"] = len(pts)
    pts, planes = _remove_planes(pts, cfg, seed)
    counts["no_planes"] = len(pts)
    belt_z = tuple(float(-p[3] / p[2]) for p in planes)
    if len(pts) <= cfg.outlier_neighbours:
        return Detection((), pts, np.full(len(pts), -1), belt_z, counts)
    _, keep = _cloud(pts).remove_statistical_outlier(cfg.outlier_neighbours, cfg.outlier_std_ratio)
    pts = pts[np.sort(np.asarray(keep, dtype=int))]
    counts["no_outliers"] = len(pts)
    labels = np.asarray(_cloud(pts).cluster_dbscan(cfg.cluster_eps_m, cfg.cluster_min_points))
    height = _height_above(planes, pts)
    found = [labels == k for k in range(int(labels.max(initial=-1)) + 1)]
    clusters = [
        m
        for m in _merge_overlapping(pts, found)
        if m.sum() >= cfg.min_cluster_points and height[m].max() >= cfg.min_height_m
    ]
    clusters.sort(key=lambda m: -int(m.sum()))
    out_labels = np.full(len(pts), -1)
    boxes = []
    for i, members in enumerate(clusters):
        out_labels[members] = i
        floor = float(np.median(pts[members, 2] - height[members])) if planes else None
        boxes.append(AABB.of_points(pts[members], floor_z=floor))
    counts["objects"] = len(boxes)
    return Detection(tuple(boxes), pts, out_labels, belt_z, counts)
