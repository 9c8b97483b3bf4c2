"""How close two objects may lie and still be told apart (Sec. 5.5, Fig. 5.17).

The detector assumes that a cluster of close points is one object. Two copies of an
object are laid one behind the other along the belts (`PairScene`) with a clear gap g
between their AABBs; the camera looks at the pair's midpoint from a given servo angle.
`min_separation` returns the smallest g on a grid from which on (every larger grid value
too) the detector reports two boxes, each within `match_m` of one object's true AABB.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from transfertwin.perception._camera import DepthCamera
from transfertwin.perception._detector import DetectorConfig, detect
from transfertwin.perception._frames import camera_pose
from transfertwin.perception._pair import PairScene
from transfertwin.perception._workspace import Workspace

__all__ = ["SeparationResult", "aim_point_x", "min_separation", "told_apart"]


@dataclass(frozen=True)
class SeparationResult:
    """The separation study at one camera angle.

    Attributes:
        alpha_deg: Servo angle.
        centre_x_m: Where the pair's midpoint lay.
        gaps_m: The gap grid.
        apart: (len(gaps_m),) whether the two objects were told apart at each gap.
        min_gap_m: Smallest gap from which on all were told apart (NaN: never).
    """

    alpha_deg: float
    centre_x_m: float
    gaps_m: tuple[float, ...]
    apart: tuple[bool, ...]
    min_gap_m: float


def aim_point_x(camera: DepthCamera, alpha_rad: float, z_m: float) -> float:
    """Where (x in F_T) the optical axis crosses the height `z_m` at servo angle α."""
    pose = camera_pose(camera.rig, alpha_rad)
    origin, axis = pose[:3, 3], pose[:3, 2]
    return float(origin[0] + (z_m - origin[2]) / axis[2] * axis[0])


def told_apart(boxes, truth, match_m: float) -> bool:
    """True if there are exactly two boxes and each matches a distinct true box."""
    if len(boxes) != 2:
        return False
    a, b = truth
    direct = max(boxes[0].corner_error(a), boxes[1].corner_error(b))
    swapped = max(boxes[0].corner_error(b), boxes[1].corner_error(a))
    return min(direct, swapped) <= match_m


def min_separation(
    scene: PairScene,
    camera: DepthCamera,
    workspace: Workspace,
    alpha_deg: float,
    gaps_m: Sequence[float],
    *,
    face: str = "front",
    theta_deg: float = 90.0,
    x_range_m: tuple[float, float] = (-0.45, -0.2),
    cfg: DetectorConfig | None = None,
    match_m: float = 0.03,
    seed: int = 0,
) -> SeparationResult:
    """The separation study at one servo angle (see the module docstring).

    The pair's midpoint is put where the optical axis meets the objects' mid-height,
    clipped to `x_range_m` (so that both lie on the TM's belts).
    """
    alpha = math.radians(alpha_deg)
    _, pts = scene.posed_verts(face, math.radians(theta_deg))
    mid_z = 0.5 * float(np.ptp(pts[:, 2]))
    centre = min(max(aim_point_x(camera, alpha, mid_z), x_range_m[0]), x_range_m[1])
    apart = []
    for k, gap in enumerate(gaps_m):
        truth = scene.place(face, math.radians(theta_deg), centre, gap)
        view = camera.capture(alpha, seed + k)
        apart.append(told_apart(detect([view], workspace, cfg, seed=seed).boxes, truth, match_m))
    min_gap = math.nan
    for k in range(len(apart) - 1, -1, -1):
        if not apart[k]:
            break
        min_gap = float(gaps_m[k])
    return SeparationResult(alpha_deg, centre, tuple(map(float, gaps_m)), tuple(apart), min_gap)
