"""Line segmentation of a laser scan by split-and-merge (Sec. 5.4.1, Fig. 5.10b).

1. Breakpoints: the ordered echoes are cut where two neighbours are further apart than the
   adaptive breakpoint distance of Borges & Aldon (2004), r·sin Δφ / sin(λ − Δφ) + 3·√2·σ with
   λ = 10° (√2: both neighbours carry range noise), or where more than `max_missing` beams in a
   row gave no echo.
2. Split: a cluster is cut recursively at the point furthest from the chord through its ends
   while that distance exceeds `split_m`.
3. Merge: neighbouring pieces whose joint total-least-squares line fits all their points within
   `split_m` are joined.
4. Each piece with at least `min_points` echoes and `min_length_m` becomes a `LineSegment`,
   fitted by total least squares; its ends are the first and last echo projected on the line.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

__all__ = ["LineSegment", "SegmentationConfig", "fit_line", "split_and_merge"]


@dataclass(frozen=True)
class SegmentationConfig:
    """Thresholds of the split-and-merge segmentation (see the module docstring).

    Attributes:
        split_m: Largest point-to-line distance inside one line, m.
        lambda_rad: Worst incidence angle λ of the adaptive breakpoint detector, rad.
        range_sd_m: Range noise σ used in the breakpoint distance, m.
        max_missing: Longest run of missing echoes inside one line.
        min_points: Fewest echoes on a line.
        min_length_m: Shortest line, m.
    """

    split_m: float = 0.05
    lambda_rad: float = math.radians(10.0)
    range_sd_m: float = 0.012
    max_missing: int = 3
    min_points: int = 6
    min_length_m: float = 0.1


@dataclass(frozen=True)
class LineSegment:
    """A fitted line piece in the scan's frame.

    Attributes:
        start, end: End points (2,) in scan order (counter-clockwise), m.
        centroid: Mean of the echoes (2,), m.
        direction: Unit vector (2,) from start to end.
        n_points: Echoes on the line.
        rms_m: Root-mean-square distance of the echoes to the line, m.
    """

    start: np.ndarray
    end: np.ndarray
    centroid: np.ndarray
    direction: np.ndarray
    n_points: int
    rms_m: float

    @property
    def length_m(self) -> float:
        """Distance between the ends, m."""
        return float(np.linalg.norm(self.end - self.start))


def fit_line(points: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Total-least-squares line through points (N, 2).

    Returns:
        Centroid (2,), unit direction (2,) and the signed distances (N,) to the line.
    """
    c = points.mean(axis=0)
    _, _, vt = np.linalg.svd(points - c, full_matrices=False)
    d = vt[0]
    normal = np.array([-d[1], d[0]])
    return c, d, (points - c) @ normal


def _clusters(points: np.ndarray, ranges: np.ndarray, step: float, cfg: SegmentationConfig):
    """Index arrays of the breakpoint-separated clusters (valid echoes only)."""
    idx = np.flatnonzero(np.isfinite(ranges))
    if len(idx) == 0:
        return []
    a, b = idx[:-1], idx[1:]
    dphi = step * (b - a)
    limit = ranges[a] * np.sin(dphi) / np.sin(np.maximum(cfg.lambda_rad - dphi, 1e-3))
    limit += 3 * math.sqrt(2) * cfg.range_sd_m
    gap = np.linalg.norm(points[b] - points[a], axis=1)
    cut = (gap > limit) | (b - a - 1 > cfg.max_missing)
    return np.split(idx, np.flatnonzero(cut) + 1)


def _split(points: np.ndarray, idx: np.ndarray, split_m: float) -> list[np.ndarray]:
    """Recursive split at the point furthest from the end-point chord."""
    if len(idx) < 3:
        return [idx]
    p0, p1 = points[idx[0]], points[idx[-1]]
    chord = p1 - p0
    n = np.linalg.norm(chord)
    if n < 1e-9:
        return [idx]
    dist = np.abs((points[idx] - p0) @ np.array([-chord[1], chord[0]]) / n)
    k = int(np.argmax(dist))
    if dist[k] <= split_m or k in (0, len(idx) - 1):
        return [idx]
    return _split(points, idx[: k + 1], split_m) + _split(points, idx[k:], split_m)


def _merge(points: np.ndarray, pieces: list[np.ndarray], split_m: float) -> list[np.ndarray]:
    """Join neighbours whose common line fits within `split_m`."""
    out = [pieces[0]]
    for piece in pieces[1:]:
        joined = np.unique(np.concatenate([out[-1], piece]))
        _, _, res = fit_line(points[joined])
        if np.max(np.abs(res)) <= split_m:
            out[-1] = joined
        else:
            out.append(piece)
    return out


def split_and_merge(
    points: np.ndarray, ranges: np.ndarray, step_rad: float, cfg: SegmentationConfig
) -> list[LineSegment]:
    """Line segments of one scan.

    Args:
        points: Echoes (N, 2) in beam order (NaN rows for missing echoes), m.
        ranges: Ranges (N,) (NaN: no echo), m.
        step_rad: Angle between beams, rad.
        cfg: Thresholds.
    """
    lines = []
    for cluster in _clusters(points, ranges, step_rad, cfg):
        if len(cluster) < cfg.min_points:
            continue
        for piece in _merge(points, _split(points, cluster, cfg.split_m), cfg.split_m):
            if len(piece) < cfg.min_points:
                continue
            c, d, res = fit_line(points[piece])
            ends = (points[piece[[0, -1]]] - c) @ d
            if ends[1] < ends[0]:
                d, ends = -d, -ends
            start, end = c + ends[0] * d, c + ends[1] * d
            if np.linalg.norm(end - start) < cfg.min_length_m:
                continue
            rms = float(np.sqrt(np.mean(res**2)))
            lines.append(LineSegment(start, end, c, d, len(piece), rms))
    return lines
