"""The 2-D laser scanner at the robot's front-left corner: exact ray casting against the
floor's solids, with a documented noise model.

Noise model (values typical of an industrial safety scanner, e.g. a 270° unit with 0.5°
steps; the study gives none):

- range noise: independent Gaussian per beam and sweep, σ = 12 mm (the datasheets' statistical
  error);
- systematic range error: a smooth function of the beam angle, fixed for one docking run
  (warm-up, temperature, surface): a random Fourier series b(φ) = Σ_{k=0..3} a_k cos kφ + b_k sin kφ
  with coefficients N(0, σ²/7), so that b has a pointwise SD of σ = 8 mm (datasheets quote a
  systematic error of about ±20–30 mm as a bound). Unlike the statistical part it does not average
  out over beams or sweeps, so it tilts and shifts fitted lines;
- no echo beyond `max_incidence_rad` (85°) from the surface normal (grazing beams) and outside
  [min_range_m, max_range_m];
- mounting: the scanner's true yaw differs from the one the robot's software assumes by
  `mount_yaw_error_rad` (an extrinsic calibration error, fixed per robot; 0.5° by default).

All randomness comes from the generator passed in, so a scan is a pure function of its seed.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from transfertwin._errors import InputError

__all__ = ["LaserConfig", "Scan", "cast_rays", "scan"]


@dataclass(frozen=True)
class LaserConfig:
    """Scanner geometry and noise (see the module docstring).

    Attributes:
        fov_rad: Field of view, centred on the scanner's zero direction, rad.
        step_rad: Angle between beams, rad.
        min_range_m, max_range_m: Valid range, m.
        range_sd_m: 1σ range noise, m.
        max_incidence_rad: Largest angle to the surface normal that still returns an echo.
        systematic_sd_m: Pointwise 1σ of the systematic range error, m.
        systematic_order: Highest harmonic of the systematic error over the beam angle.
        mount_yaw_error_rad: True minus assumed scanner yaw, rad.
    """

    fov_rad: float = math.radians(270.0)
    step_rad: float = math.radians(0.5)
    min_range_m: float = 0.05
    max_range_m: float = 10.0
    range_sd_m: float = 0.012
    max_incidence_rad: float = math.radians(85.0)
    systematic_sd_m: float = 0.008
    systematic_order: int = 3
    mount_yaw_error_rad: float = math.radians(0.5)

    def __post_init__(self) -> None:
        if not (0 < self.step_rad < self.fov_rad <= 2 * math.pi):
            raise InputError("LaserConfig: need 0 < step < field of view <= 360°")
        if self.range_sd_m < 0 or not (0 <= self.min_range_m < self.max_range_m):
            raise InputError("LaserConfig: range noise >= 0 and 0 <= min range < max range")

    def range_bias(self, rng: np.random.Generator) -> np.ndarray:
        """One draw of the systematic range error per beam (N,), m (see the module docstring)."""
        k = np.arange(self.systematic_order + 1)
        n = 2 * self.systematic_order + 1
        a, b = rng.normal(0.0, self.systematic_sd_m / math.sqrt(n), (2, len(k)))
        phi = self.angles()[:, None] * k[None, :]
        return (np.cos(phi) @ a) + (np.sin(phi) @ b)

    def angles(self) -> np.ndarray:
        """Beam angles (N,) in the scanner frame, rad, ordered counter-clockwise."""
        n = round(self.fov_rad / self.step_rad) + 1
        return -self.fov_rad / 2.0 + self.step_rad * np.arange(n)


@dataclass(frozen=True)
class Scan:
    """One sweep: beam angles (N,) in the scanner frame (rad) and ranges (N,) in m, NaN
    where no echo came back."""

    angles: np.ndarray
    ranges: np.ndarray

    def points(self) -> np.ndarray:
        """Echo points (N, 2) in the scanner frame, NaN rows for missing echoes."""
        return np.stack([self.ranges * np.cos(self.angles), self.ranges * np.sin(self.angles)], 1)


def cast_rays(
    origin: np.ndarray, directions: np.ndarray, segments: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Exact first hits of rays against segments.

    Args:
        origin: Ray origin (2,), m.
        directions: Unit directions (N, 2).
        segments: (S, 2, 2) segment end points, m.

    Returns:
        Distance to the first hit (N,) (inf: none) and |cos| of the incidence angle (N,).
    """
    p, e = segments[:, 0], segments[:, 1] - segments[:, 0]
    po = p - origin
    d = directions[:, None, :]
    denom = d[..., 0] * e[None, :, 1] - d[..., 1] * e[None, :, 0]
    with np.errstate(divide="ignore", invalid="ignore"):
        t = (po[None, :, 0] * e[None, :, 1] - po[None, :, 1] * e[None, :, 0]) / denom
        u = (po[None, :, 0] * d[..., 1] - po[None, :, 1] * d[..., 0]) / denom
    ok = (np.abs(denom) > 1e-12) & (t > 1e-9) & (u >= 0.0) & (u <= 1.0)
    t = np.where(ok, t, np.inf)
    k = np.argmin(t, axis=1)
    rows = np.arange(len(directions))
    dist = t[rows, k]
    cos_inc = np.abs(denom[rows, k]) / np.maximum(np.linalg.norm(e[k], axis=1), 1e-12)
    return dist, cos_inc


def scan(
    segments: np.ndarray,
    laser_pose: np.ndarray,
    cfg: LaserConfig,
    rng: np.random.Generator | None,
    bias: np.ndarray | None = None,
) -> Scan:
    """One sweep from the scanner's true pose in the world.

    Args:
        segments: The floor's solid edges (S, 2, 2), m.
        laser_pose: True scanner pose (x, y, yaw) in the world.
        cfg: Geometry and noise.
        rng: Source of the statistical noise; None leaves it out.
        bias: Systematic range error per beam (N,) from `LaserConfig.range_bias`, m.
    """
    angles = cfg.angles()
    world = laser_pose[2] + angles
    dirs = np.stack([np.cos(world), np.sin(world)], axis=1)
    dist, cos_inc = cast_rays(laser_pose[:2], dirs, segments)
    if bias is not None:
        dist = dist + bias
    if rng is not None:
        dist = dist + rng.normal(0.0, cfg.range_sd_m, len(dist))
    valid = (
        np.isfinite(dist)
        & (dist >= cfg.min_range_m)
        & (dist <= cfg.max_range_m)
        & (cos_inc >= math.cos(cfg.max_incidence_rad))
    )
    return Scan(angles, np.where(valid, dist, np.nan))
