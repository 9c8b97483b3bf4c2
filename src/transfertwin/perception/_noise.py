"""The depth camera's noise and dropout model (docs/perception.md, "Noise model").

A time-of-flight camera such as the study's Azure Kinect returns, per pixel, either a
depth or nothing. We model three effects, each with its own parameter:

- range: pixels nearer than `min_range_m` or farther than `max_range_m` return nothing;
- depth noise: a zero-mean Gaussian along the ray whose standard deviation grows in
  proportion to the depth, σ(z) = `sigma_rel` · z (0.2 % by default: about 1.1 mm at the
  0.55 m from camera to belt; the Kinect's datasheet states ≤ 17 mm random error over its
  whole range, near-range measurements are far better);
- dropout: every pixel independently returns nothing with probability `dropout`.

Every draw comes from a `numpy.random.Generator` built from an explicit seed, so the same
seed gives the same cloud bit for bit. `DepthNoise.clean()` switches noise and dropout off.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from transfertwin._errors import InputError

__all__ = ["DepthNoise", "apply_depth_noise"]


@dataclass(frozen=True)
class DepthNoise:
    """Noise and dropout parameters of the depth camera.

    Attributes:
        sigma_rel: Standard deviation of the depth noise per metre of depth (-).
        dropout: Probability that a pixel returns no depth (-).
        min_range_m, max_range_m: The depth range that returns a value (m).
    """

    sigma_rel: float = 0.002
    dropout: float = 0.01
    min_range_m: float = 0.25
    max_range_m: float = 3.0

    def __post_init__(self) -> None:
        ok = all(math.isfinite(v) for v in (self.sigma_rel, self.dropout, self.min_range_m))
        if not ok or self.sigma_rel < 0 or not 0 <= self.dropout < 1:
            raise InputError("DepthNoise: sigma_rel must be >= 0 and dropout in [0, 1)")
        if not 0 <= self.min_range_m < self.max_range_m:
            raise InputError("DepthNoise: need 0 <= min_range_m < max_range_m")

    @classmethod
    def clean(cls) -> DepthNoise:
        """No depth noise and no dropout (the range limits stay)."""
        return cls(sigma_rel=0.0, dropout=0.0)


def apply_depth_noise(depth_m: np.ndarray, noise: DepthNoise, seed: int) -> np.ndarray:
    """A noisy copy of a depth image (H, W) in metres; pixels without depth are NaN.

    Args:
        depth_m: Rendered depth along the optical axis (m); non-finite means no return.
        noise: The model.
        seed: Seed of this frame's draws.
    """
    depth = np.asarray(depth_m, dtype=np.float64).copy()
    out_of_range = ~np.isfinite(depth) | (depth < noise.min_range_m) | (depth > noise.max_range_m)
    rng = np.random.default_rng(seed)
    if noise.sigma_rel > 0.0:
        depth += rng.standard_normal(depth.shape) * (noise.sigma_rel * np.nan_to_num(depth))
    if noise.dropout > 0.0:
        out_of_range |= rng.random(depth.shape) < noise.dropout
    depth[out_of_range] = np.nan
    return depth
