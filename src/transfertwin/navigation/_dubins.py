"""Dubins paths: the shortest forward paths between two poses with a bounded curvature
(Dubins 1957; the six words LSL, RSR, LSR, RSL, RLR, LRL in the normalised form of
Shkel & Lumelsky 2001). The global planner uses them as its analytic expansion and its
obstacle-free heuristic.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

__all__ = ["DubinsPath", "dubins_shortest", "sample_segments"]

_TWO_PI = 2.0 * math.pi


def _mod(a: float) -> float:
    return a % _TWO_PI


@dataclass(frozen=True)
class DubinsPath:
    """A Dubins path: its word ('LSR', ...), the three segment lengths (m) and the radius."""

    word: str
    lengths_m: tuple[float, float, float]
    radius_m: float

    @property
    def length_m(self) -> float:
        """Total length, m."""
        return sum(self.lengths_m)

    def segments(self) -> list[tuple[float, float]]:
        """(curvature 1/m, length m) of each piece."""
        k = {"L": 1.0 / self.radius_m, "S": 0.0, "R": -1.0 / self.radius_m}
        return [(k[c], s) for c, s in zip(self.word, self.lengths_m, strict=True)]


def _words(a: float, b: float, d: float) -> dict[str, tuple[float, float, float] | None]:
    sa, sb, ca, cb = math.sin(a), math.sin(b), math.cos(a), math.cos(b)
    cab = math.cos(a - b)
    out: dict[str, tuple[float, float, float] | None] = {}
    p2 = 2 + d * d - 2 * cab + 2 * d * (sa - sb)
    if p2 >= 0:
        t1 = math.atan2(cb - ca, d + sa - sb)
        out["LSL"] = (_mod(t1 - a), math.sqrt(p2), _mod(b - t1))
    p2 = 2 + d * d - 2 * cab + 2 * d * (sb - sa)
    if p2 >= 0:
        t1 = math.atan2(ca - cb, d - sa + sb)
        out["RSR"] = (_mod(a - t1), math.sqrt(p2), _mod(t1 - b))
    p2 = -2 + d * d + 2 * cab + 2 * d * (sa + sb)
    if p2 >= 0:
        p = math.sqrt(p2)
        t0 = math.atan2(-ca - cb, d + sa + sb) - math.atan2(-2.0, p)
        out["LSR"] = (_mod(t0 - a), p, _mod(t0 - b))
    p2 = -2 + d * d + 2 * cab - 2 * d * (sa + sb)
    if p2 >= 0:
        p = math.sqrt(p2)
        t0 = math.atan2(ca + cb, d - sa - sb) - math.atan2(2.0, p)
        out["RSL"] = (_mod(a - t0), p, _mod(b - t0))
    c = (6 - d * d + 2 * cab + 2 * d * (sa - sb)) / 8
    if abs(c) <= 1:
        phi = math.atan2(ca - cb, d - sa + sb)
        p = _mod(_TWO_PI - math.acos(c))
        t = _mod(a - phi + _mod(p / 2))
        out["RLR"] = (t, p, _mod(a - b - t + _mod(p)))
    c = (6 - d * d + 2 * cab + 2 * d * (sb - sa)) / 8
    if abs(c) <= 1:
        phi = math.atan2(ca - cb, d + sa - sb)
        p = _mod(_TWO_PI - math.acos(c))
        t = _mod(-a - phi + p / 2)
        out["LRL"] = (t, p, _mod(_mod(b) - a - t + _mod(p)))
    return out


def dubins_shortest(q0: np.ndarray, q1: np.ndarray, radius_m: float) -> DubinsPath:
    """The shortest Dubins path from pose q0 to q1 (x, y, θ) with turning radius `radius_m`."""
    dx, dy = q1[0] - q0[0], q1[1] - q0[1]
    d = math.hypot(dx, dy) / radius_m
    th = _mod(math.atan2(dy, dx)) if d > 0 else 0.0
    a, b = _mod(q0[2] - th), _mod(q1[2] - th)
    best = None
    for word, lens in _words(a, b, d).items():
        if lens is not None and (best is None or sum(lens) < sum(best[1])):
            best = (word, lens)
    word, lens = best  # LSL or RSR always exists
    return DubinsPath(word, tuple(v * radius_m for v in lens), radius_m)


def sample_segments(
    q0: np.ndarray, segments: list[tuple[float, float]], step_m: float
) -> tuple[np.ndarray, np.ndarray]:
    """Poses along constant-curvature pieces, exactly integrated.

    Args:
        q0: Start pose (3,).
        segments: (curvature 1/m, length m) pieces.
        step_m: Largest spacing between samples, m.

    Returns:
        Poses (M, 3) starting with q0 and ending at the end of the last piece, and the
        curvature (M,) of the piece leading to each pose (the first repeats the second).
    """
    poses, curv = [np.asarray(q0, dtype=float)], [segments[0][0] if segments else 0.0]
    x, y, th = (float(v) for v in q0)
    for k, length in segments:
        n = max(1, math.ceil(length / step_m - 1e-9))
        for i in range(1, n + 1):
            s = length * i / n
            if abs(k) < 1e-12:
                px, py, pt = x + s * math.cos(th), y + s * math.sin(th), th
            else:
                pt = th + k * s
                px = x + (math.sin(pt) - math.sin(th)) / k
                py = y - (math.cos(pt) - math.cos(th)) / k
            poses.append(np.array([px, py, pt]))
            curv.append(k)
        x, y, th = px, py, pt
    out = np.array(poses)
    out[:, 2] = (out[:, 2] + math.pi) % _TWO_PI - math.pi
    return out, np.array(curv)
