"""Solid primitives for the procedural cores, built with manifold3d.

Every solid is a closed `manifold3d.Manifold` in metres. Prisms run along the
x axis (the motor axis of a core): a 2-D profile drawn in the (y, z) plane is
extruded from ``x0`` to ``x1``. The axis permutations below are exact integer
matrices, so a profile vertex at z = -r stays at exactly z = -r.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
from manifold3d import CrossSection, Manifold

__all__ = [
    "box",
    "circle",
    "gear_profile",
    "prism_x",
    "rod_y",
    "sphere",
    "stadium",
    "union_all",
]

# (y, z, extrusion) -> (x, y, z): extrusion axis to +x, profile u -> y, v -> z.
_PROFILE_TO_X = np.array([[0.0, 0.0, 1.0, 0.0], [1.0, 0.0, 0.0, 0.0], [0.0, 1.0, 0.0, 0.0]])
# Cylinder axis z -> -y (a rod sticking out sideways, towards -y); det = +1.
_Z_TO_MINUS_Y = np.array([[1.0, 0.0, 0.0, 0.0], [0.0, 0.0, -1.0, 0.0], [0.0, 1.0, 0.0, 0.0]])


def circle(
    radius_m: float, segments: int, centre_yz: tuple[float, float] = (0.0, 0.0)
) -> CrossSection:
    """Regular polygon approximating a circle in the (y, z) plane.

    Args:
        radius_m: Circumradius in metres.
        segments: Number of polygon edges; a multiple of 4 puts vertices at
            exactly z = ±radius.
        centre_yz: Centre (y, z) in metres.

    Returns:
        The 2-D profile.
    """
    return CrossSection.circle(radius_m, segments).translate(centre_yz)


def stadium(
    start_yz: tuple[float, float], end_yz: tuple[float, float], radius_m: float, segments: int
) -> CrossSection:
    """Convex hull of two equal circles (a slot or lug outline).

    Args:
        start_yz: First circle centre (y, z) in metres.
        end_yz: Second circle centre (y, z) in metres.
        radius_m: Radius of both circles in metres.
        segments: Edges per circle.

    Returns:
        The 2-D profile.
    """
    return CrossSection.batch_hull(
        [circle(radius_m, segments, start_yz), circle(radius_m, segments, end_yz)]
    )


def gear_profile(teeth: int, module_m: float) -> CrossSection:
    """Spur-gear outline with trapezoidal teeth, centred on the origin.

    Tip radius ``m (z + 2) / 2`` and root radius ``m (z - 2.5) / 2`` follow the
    standard involute proportions (ISO 53); the flanks are straight.

    Args:
        teeth: Number of teeth z (>= 6).
        module_m: Module m in metres.

    Returns:
        The 2-D profile.
    """
    r_tip = module_m * (teeth + 2) / 2.0
    r_root = module_m * (teeth - 2.5) / 2.0
    pitch = 2.0 * math.pi / teeth
    points: list[tuple[float, float]] = []
    for k in range(teeth):
        centre = k * pitch
        for offset, radius in ((-0.30, r_root), (-0.13, r_tip), (0.13, r_tip), (0.30, r_root)):
            angle = centre + offset * pitch
            points.append((radius * math.cos(angle), radius * math.sin(angle)))
    return CrossSection([np.asarray(points)])


def prism_x(profile: CrossSection, x0_m: float, x1_m: float, scale_end: float = 1.0) -> Manifold:
    """Extrude a (y, z) profile along +x.

    Args:
        profile: Profile in the (y, z) plane, metres.
        x0_m: Start of the prism in metres.
        x1_m: End of the prism in metres (> ``x0_m``).
        scale_end: Uniform scale of the profile at ``x1_m`` about the (y, z)
            origin (1 = prism, < 1 = frustum).

    Returns:
        The solid.
    """
    solid = profile.extrude(x1_m - x0_m, scale_top=(scale_end, scale_end))
    return solid.transform(_PROFILE_TO_X).translate((x0_m, 0.0, 0.0))


def rod_y(
    radius_m: float, length_m: float, base_xyz: tuple[float, float, float], segments: int
) -> Manifold:
    """Cylinder from ``base_xyz`` along -y (a sideways terminal stud).

    Args:
        radius_m: Radius in metres.
        length_m: Length in metres.
        base_xyz: Centre of the base disc (x, y, z) in metres.
        segments: Edges around the circumference.

    Returns:
        The solid.
    """
    rod = Manifold.cylinder(length_m, radius_m, radius_m, segments)
    return rod.transform(_Z_TO_MINUS_Y).translate(base_xyz)


def sphere(radius_m: float, centre_xyz: tuple[float, float, float], segments: int) -> Manifold:
    """Sphere (geodesic polyhedron) of radius ``radius_m`` at ``centre_xyz`` (m)."""
    return Manifold.sphere(radius_m, segments).translate(centre_xyz)


def box(lo_xyz: Sequence[float], hi_xyz: Sequence[float]) -> Manifold:
    """Axis-aligned box between the corners ``lo_xyz`` and ``hi_xyz`` (m)."""
    size = tuple(float(h - lo) for lo, h in zip(lo_xyz, hi_xyz, strict=True))
    return Manifold.cube(size).translate(tuple(float(v) for v in lo_xyz))


def union_all(parts: Sequence[Manifold]) -> Manifold:
    """Boolean union folded left to right (a fixed order keeps results repeatable)."""
    result = parts[0]
    for part in parts[1:]:
        result = result + part
    return result
