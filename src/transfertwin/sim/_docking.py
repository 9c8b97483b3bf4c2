"""Where the transfer unit lies as seen from a docked transport module (Eq. 6.11).

Homogeneous 2-D transforms, poses as (x, y, yaw). The docking error ξ is the pose of the
docked TM centre F_D in its goal F_D_G, so the TU seen from F_D is

    T(D→TU) = ξ⁻¹ · T(D_G→TU),

ξ⁻¹ on the left: the error rotates about the TM's centre, not its tip, so a yaw error also
shifts the tip sideways. The simulation world frame is the TM tip frame F_T, which sits
`tip_to_centre_m` ahead of F_D.
"""

from __future__ import annotations

import numpy as np

from transfertwin.sim._config import DockingError

__all__ = ["compose", "invert", "pose_matrix", "tu_pose_in_tip_frame"]


def pose_matrix(x: float, y: float, yaw: float) -> np.ndarray:
    """Homogeneous 2-D transform (3, 3) of a pose (m, m, rad)."""
    c, s = np.cos(yaw), np.sin(yaw)
    return np.array([[c, -s, x], [s, c, y], [0.0, 0.0, 1.0]])


def invert(t: np.ndarray) -> np.ndarray:
    """Inverse of a homogeneous 2-D rigid transform (3, 3)."""
    r = t[:2, :2]
    out = np.eye(3)
    out[:2, :2] = r.T
    out[:2, 2] = -r.T @ t[:2, 2]
    return out


def compose(*ts: np.ndarray) -> np.ndarray:
    """Product of transforms, left to right."""
    out = np.eye(3)
    for t in ts:
        out = out @ t
    return out


def tu_pose_in_tip_frame(
    error: DockingError, gap_m: float, tip_to_centre_m: float
) -> tuple[float, float, float]:
    """Pose (x, y, yaw) of the TU frame in F_T for a docking error (Eq. 6.11).

    The TU frame has its origin at the TU's near belt end on the belt surface and its x
    axis pointing away from the TM. Nominally (ξ = 0) it sits at (gap_m, 0, 0).

    Args:
        error: Docking error ξ.
        gap_m: Nominal gap d_gap (m).
        tip_to_centre_m: Distance from the TM centre F_D forward to the tip F_T (m).

    Returns:
        (x_m, y_m, yaw_rad) of the TU frame in F_T.
    """
    t_d_tip = pose_matrix(tip_to_centre_m, 0.0, 0.0)
    t_goal_tu = pose_matrix(tip_to_centre_m + gap_m, 0.0, 0.0)
    xi = pose_matrix(error.x_m, error.y_m, error.theta_rad)
    t_tip_tu = compose(invert(t_d_tip), invert(xi), t_goal_tu)
    yaw = float(np.arctan2(t_tip_tu[1, 0], t_tip_tu[0, 0]))
    return float(t_tip_tu[0, 2]), float(t_tip_tu[1, 2]), yaw
