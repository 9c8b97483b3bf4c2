"""The object tracker (Sec. 5.4.3): detections matched to tracks, a Kalman filter between.

Each track carries a Kalman filter on the AABB centre (x, y) in F_T. The belts move an
object at their own speed, so the prediction uses the belt velocity as a *control input*:

    predict:  x⁻ = x + B u,  B = Δt · I,  u = (v_x, v_y) of the belt under the object
              P⁻ = P + Q Δt,  Q = q² I          (slip and placement disturbances)
    update:   K = P⁻ (P⁻ + R)⁻¹,  R = r² I      (the detector's centre error)
              x = x⁻ + K (z − x⁻),  P = (I − K) P⁻

(the standard linear Kalman filter with H = I; the study names the filter and its control
input but gives no equations). Matching is a minimum-cost assignment (Hungarian method) on
the distance between each detection's centre and each track's predicted centre, gated at
`gate_m`. A track that finds no detection keeps its prediction: this is what bridges
frames in which the detector misses the object while the belt runs. After `max_missed`
misses in a row a track is dropped; an unmatched detection opens a new track.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np
from scipy.optimize import linear_sum_assignment

from transfertwin.perception._aabb import AABB

__all__ = ["Track", "Tracker", "TrackerConfig"]

Velocity = Callable[[np.ndarray], np.ndarray]


@dataclass(frozen=True)
class TrackerConfig:
    """Tracker parameters.

    Attributes:
        gate_m: Largest centre distance at which a detection can match a track (m).
        max_missed: Consecutive missed frames after which a track is dropped.
        process_sigma_m_s: q: growth of the position uncertainty (m per √s).
        measurement_sigma_m: r: standard deviation of a detected centre (m).
    """

    gate_m: float = 0.04
    max_missed: int = 15
    process_sigma_m_s: float = 0.02
    measurement_sigma_m: float = 0.005


@dataclass
class Track:
    """One tracked object: id, filtered centre (2,), covariance (2, 2), last box."""

    track_id: int
    mean: np.ndarray
    cov: np.ndarray
    box: AABB
    missed: int = 0
    hits: int = 1

    def aabb(self) -> AABB:
        """The last detected box moved to the filtered centre."""
        z = self.box.centre[2]
        return AABB((float(self.mean[0]), float(self.mean[1]), z), self.box.half,
                    self.box.n_points)  # fmt: skip


class Tracker:
    """Keeps `Track`s across frames (Sec. 5.4.3)."""

    def __init__(self, cfg: TrackerConfig | None = None) -> None:
        self.cfg = cfg if cfg is not None else TrackerConfig()
        self.tracks: list[Track] = []
        self._next_id = 1

    def _predict(self, dt_s: float, velocity: Velocity) -> None:
        q2 = self.cfg.process_sigma_m_s**2
        for tr in self.tracks:
            u = np.asarray(velocity(tr.mean), dtype=float)
            tr.mean = tr.mean + dt_s * u
            tr.cov = tr.cov + q2 * dt_s * np.eye(2)

    def _update(self, tr: Track, box: AABB) -> None:
        r2 = self.cfg.measurement_sigma_m**2
        gain = tr.cov @ np.linalg.inv(tr.cov + r2 * np.eye(2))
        tr.mean = tr.mean + gain @ (np.asarray(box.centre[:2]) - tr.mean)
        tr.cov = (np.eye(2) - gain) @ tr.cov
        tr.box, tr.missed, tr.hits = box, 0, tr.hits + 1

    def _match(self, boxes: Sequence[AABB]) -> list[tuple[int, int]]:
        if not self.tracks or not boxes:
            return []
        det = np.array([b.centre[:2] for b in boxes])
        pred = np.array([t.mean for t in self.tracks])
        cost = np.linalg.norm(pred[:, None, :] - det[None, :, :], axis=2)
        rows, cols = linear_sum_assignment(cost)
        return [(r, c) for r, c in zip(rows, cols, strict=True) if cost[r, c] <= self.cfg.gate_m]

    def step(
        self,
        boxes: Sequence[AABB],
        dt_s: float,
        velocity: Velocity | tuple[float, float] = (0.0, 0.0),
    ) -> list[Track]:
        """Advance by `dt_s` with the belts' velocity, then fold in this frame's detections.

        Args:
            boxes: This frame's detections (may be empty: a missed frame).
            dt_s: Time since the previous frame (s).
            velocity: Belt velocity (v_x, v_y) in F_T (m/s), or a function of a track's
                centre (2,) giving it (objects on different belts move differently).

        Returns:
            The live tracks after this frame.
        """
        if not callable(velocity):
            fixed = np.asarray(velocity, dtype=float)
            velocity = lambda _c: fixed  # noqa: E731
        self._predict(dt_s, velocity)
        matched = self._match(boxes)
        used_tracks = {r for r, _ in matched}
        used_boxes = {c for _, c in matched}
        for r, c in matched:
            self._update(self.tracks[r], boxes[c])
        for i, tr in enumerate(self.tracks):
            if i not in used_tracks:
                tr.missed += 1
        self.tracks = [t for t in self.tracks if t.missed <= self.cfg.max_missed]
        r0 = self.cfg.measurement_sigma_m**2
        for c, box in enumerate(boxes):
            if c not in used_boxes:
                mean = np.asarray(box.centre[:2], dtype=float)
                self.tracks.append(Track(self._next_id, mean, r0 * np.eye(2), box))
                self._next_id += 1
        return list(self.tracks)

    def nearest(self, xy: Sequence[float]) -> Track | None:
        """The live track whose centre is nearest to (x, y), or None without tracks."""
        if not self.tracks:
            return None
        return min(self.tracks, key=lambda t: math.dist(t.mean, xy))
