"""The frames of the transport module's vision system (Table 5.1) and their transforms.

F_T (world) is the TM's tip frame: origin at the front tip on the belt surface, x towards
the TU, z up. The servo module is mounted at a fixed point F_S above the TM belts; F_A turns
with the servo about an axis parallel to y_T; F_C is the camera, fixed on the servo arm, with
its z axis as the optical axis (x image right, y image down, as in OpenCV).

Sign of the servo angle α: positive α turns the optical axis towards +x_T (the TU); at α = 0
it points straight down (Sec. 5.4.4). The study gives no dimensions for the mast; the default
`ServoRig` is our choice (docs/perception.md, "Frames").

Transforms are homogeneous 4x4 matrices T_XY that map coordinates in F_Y to F_X, so a point
p_C in the camera frame lies at T_TS @ T_SA(α) @ T_AC @ p_C in F_T (the chain of Eq. 5.14).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from transfertwin._errors import InputError

__all__ = ["ServoRig", "camera_pose", "t_ac", "t_sa", "t_ts"]


@dataclass(frozen=True)
class ServoRig:
    """Where the servo sits on the TM and where the camera sits on the servo arm.

    Attributes:
        servo_xyz_m: Origin of F_S in F_T (m): the servo's axis passes through it, parallel
            to y_T. Default 0.20 m behind the tip, centred across the belts, 0.60 m above
            the belt surface.
        camera_offset_m: (e_x, e_z): the camera centre in F_A, e_x along the camera's x axis
            (towards +x_T at α = 0) and e_z below the axis (m). A non-zero e_x puts the
            optical axis beside the servo axis, which is what makes Eq. 5.14 non-trivial.
        alpha_limits_deg: The servo's range (degrees).
    """

    servo_xyz_m: tuple[float, float, float] = (-0.20, 0.0, 0.60)
    camera_offset_m: tuple[float, float] = (0.03, 0.05)
    alpha_limits_deg: tuple[float, float] = (-60.0, 60.0)

    def __post_init__(self) -> None:
        lo, hi = self.alpha_limits_deg
        if not (-90.0 <= lo < hi <= 90.0):
            raise InputError(f"ServoRig.alpha_limits_deg must lie in [-90, 90], got {lo}, {hi}")
        if self.servo_xyz_m[2] <= self.camera_offset_m[1]:
            raise InputError("ServoRig: the camera must hang above the belt surface")

    def clip(self, alpha_rad: float) -> float:
        """α limited to the servo's range (rad)."""
        lo, hi = (math.radians(a) for a in self.alpha_limits_deg)
        return min(max(alpha_rad, lo), hi)


def t_ts(rig: ServoRig) -> np.ndarray:
    """T_TS (4, 4): the servo mount F_S in F_T, a translation (axes parallel to F_T)."""
    out = np.eye(4)
    out[:3, 3] = rig.servo_xyz_m
    return out


def t_sa(alpha_rad: float) -> np.ndarray:
    """T_SA(α) (4, 4): rotation of the servo by α about y; positive α lifts -z towards +x.

    In the (x, z) plane this is the 2-D rotation by α: (x, z) → (x cos α − z sin α,
    x sin α + z cos α), so the downward axis (0, −1) becomes (sin α, −cos α).
    """
    c, s = math.cos(alpha_rad), math.sin(alpha_rad)
    out = np.eye(4)
    out[0, 0], out[0, 2] = c, -s
    out[2, 0], out[2, 2] = s, c
    return out


def t_ac(rig: ServoRig) -> np.ndarray:
    """T_AC (4, 4): the camera on the servo arm: at (e_x, 0, −e_z) in F_A, turned so that
    z_C = −z_A (looking down at α = 0), x_C = x_A and y_C = −y_A (image rows run to −y_T)."""
    e_x, e_z = rig.camera_offset_m
    out = np.diag([1.0, -1.0, -1.0, 1.0])
    out[:3, 3] = (e_x, 0.0, -e_z)
    return out


def camera_pose(rig: ServoRig, alpha_rad: float) -> np.ndarray:
    """T_TC(α) = T_TS T_SA(α) T_AC (4, 4): the camera frame F_C in F_T."""
    return t_ts(rig) @ t_sa(alpha_rad) @ t_ac(rig)
