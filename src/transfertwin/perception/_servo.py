"""Visual servoing (Sec. 5.4.4): the servo angle α that points the camera at an object.

The camera turns about one axis, so the problem is 2-D in the (x, z) plane of F_T
(Fig. 5.15a). The camera is focused on the object's AABB centre F_BB when

- Eq. 5.12: the vector d from F_C to F_BB, expressed in F_C, has no x component:
  C_d = (0, d_z, 1) in 2-D homogeneous (x_C, z_C) coordinates;
- Eq. 5.13: transformed to F_BB it is the origin: BB_d = (0, 0, 1);
- Eq. 5.14: BB_d = T_TO⁻¹ T_TS T_SA(α) T_AC C_d.

Written out with D = (X, Z) = the object's (x, z) minus the servo axis's and the camera
offset (e_x, e_z) of `ServoRig`, Eq. 5.14 says D = e_x u(α) + (e_z + d_z) n(α) with the
camera's x axis u = (cos α, sin α) and optical axis n = (sin α, −cos α). Projecting on u and
n gives the closed form

    X cos α + Z sin α = e_x   →   α = atan2(Z, X) + acos(e_x / |D|),
    d_z = X sin α − Z cos α − e_z,

taking the root with d_z > 0 (the camera looks at the object, not away from it). At α = 0
the first line reads X = e_x for every Z: the servo angle does not depend on z there
(Fig. 5.15b).
"""

from __future__ import annotations

import math

import numpy as np

from transfertwin._errors import InputError
from transfertwin.perception._frames import ServoRig

__all__ = ["eq_5_14", "servo_angle", "servo_chain_2d"]


def servo_chain_2d(rig: ServoRig, alpha_rad: float) -> np.ndarray:
    """T_TS T_SA(α) T_AC (3, 3) in 2-D homogeneous (x, z) coordinates (Eq. 5.14).

    F_C's 2-D axes are (x_C, z_C); at α = 0, x_C = x_T and z_C = −z_T.
    """
    x_s, _, z_s = rig.servo_xyz_m
    e_x, e_z = rig.camera_offset_m
    c, s = math.cos(alpha_rad), math.sin(alpha_rad)
    ts = np.array([[1.0, 0.0, x_s], [0.0, 1.0, z_s], [0.0, 0.0, 1.0]])
    sa = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
    ac = np.array([[1.0, 0.0, e_x], [0.0, -1.0, -e_z], [0.0, 0.0, 1.0]])
    return ts @ sa @ ac


def eq_5_14(rig: ServoRig, alpha_rad: float, d_z: float, obj_xz: tuple[float, float]):
    """BB_d (3,) of Eq. 5.14 for C_d = (0, d_z, 1) (Eq. 5.12) and an object at (x, z) in F_T.

    The camera is focused on the object when this is (0, 0, 1) (Eq. 5.13).
    """
    t_to_inv = np.array([[1.0, 0.0, -obj_xz[0]], [0.0, 1.0, -obj_xz[1]], [0.0, 0.0, 1.0]])
    return t_to_inv @ servo_chain_2d(rig, alpha_rad) @ np.array([0.0, d_z, 1.0])


def servo_angle(rig: ServoRig, x_m: float, z_m: float) -> tuple[float, float]:
    """Solve Eq. 5.14 for (α, d_z) in closed form: the servo angle (rad) that points the
    optical axis at (x, z) in F_T, and the object's distance along that axis (m).

    α is not clipped to the servo's range (see `ServoRig.clip`).

    Raises:
        InputError: If no angle can focus the point (it lies within the camera offset of
            the servo axis, or above the camera).
    """
    x_s, _, z_s = rig.servo_xyz_m
    e_x, e_z = rig.camera_offset_m
    big_x, big_z = x_m - x_s, z_m - z_s
    r = math.hypot(big_x, big_z)
    if r <= abs(e_x):
        raise InputError(f"({x_m:.3f}, {z_m:.3f}) m is too close to the servo axis (Eq. 5.14)")
    alpha = math.atan2(big_z, big_x) + math.acos(e_x / r)
    alpha = math.remainder(alpha, 2.0 * math.pi)  # into [-π, π]
    d_z = big_x * math.sin(alpha) - big_z * math.cos(alpha) - e_z
    if d_z <= 0.0:
        raise InputError(f"({x_m:.3f}, {z_m:.3f}) m lies behind the camera (Eq. 5.14)")
    return alpha, d_z
