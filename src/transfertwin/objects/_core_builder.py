"""Constructive solid geometry of a starter-motor core from its `CoreSpec`.

Build frame (metres): x along the motor axis towards the pinion, the can/housing
junction at x = 0, the can axis on the x axis, the solenoid beside the can at
-y with its bottom at z = -can radius, so that the can and the solenoid both
rest on the plane z = -can radius ('front'). The drive-end housing is a
D-shaped casting that wraps the front of the solenoid; turned over ('back') the
core rests on the top line of the can and the top edge of the housing at the far
solenoid side, both at z = +can radius. Everything else (ears, end cap, studs,
pinion) stays inside the band |z| < can radius, so both faces are stable.
"""

from __future__ import annotations

import math

from manifold3d import CrossSection, Manifold

from transfertwin.objects._core_spec import CoreSpec, Dent
from transfertwin.objects._primitives import (
    circle,
    gear_profile,
    prism_x,
    rod_y,
    sphere,
    stadium,
    union_all,
)

__all__ = ["build_core_solid"]

_SEG_CAN = 48  # multiples of 4: vertices at exactly z = ±r
_SEG_SOLENOID = 40
_SEG_SMALL = 16
_HOUSING_INSET_M = 0.0004  # housing half-height = can radius - this
_OVERLAP_M = 0.001  # parts overlap axially so unions never meet on coplanar faces


def build_core_solid(spec: CoreSpec) -> Manifold:
    """Union of the parts of a core, minus its dents, in the build frame.

    Args:
        spec: The core specification.

    Returns:
        A closed manifold solid in metres.
    """
    parts = [
        _can(spec),
        _housing(spec),
        *_ears(spec),
        *_nose_and_pinion(spec),
        *_solenoid(spec),
        *_rear(spec),
    ]
    solid = union_all(parts)
    if spec.missing_end_cap:
        solid = solid - _open_can_end(spec)
        solid = solid + _commutator(spec)
    for dent in spec.dents:
        solid = solid - _dent_sphere(spec, dent)
    return solid


def _polar(radius: float, angle_deg: float, centre: tuple[float, float] = (0.0, 0.0)) -> tuple:
    """(y, z) of a point at ``radius`` and ``angle_deg`` (from +y towards +z) about ``centre``."""
    a = math.radians(angle_deg)
    return (centre[0] + radius * math.cos(a), centre[1] + radius * math.sin(a))


def _can(spec: CoreSpec) -> Manifold:
    """Yoke can: cylinder of the can radius from x = -can length to 0."""
    return prism_x(circle(spec.can_radius_m, _SEG_CAN), -spec.can_length_m, 0.0)


def _housing(spec: CoreSpec) -> Manifold:
    """Drive-end housing: D-shaped casting around the armature and the solenoid's front.

    Seen along x it is the convex hull of a circle of can radius - 0.4 mm (kept
    just inside the can), a corner at the far solenoid side whose top reaches
    z = can radius (the second support line on face 'back'), and the solenoid
    circle grown by ``housing_wall_m`` whose bottom stays 0.4 mm above the
    solenoid's (which carries the core on face 'front').
    """
    r_can = spec.can_radius_m
    rho = spec.housing_corner_radius_m
    wall = spec.housing_wall_m
    y_s, z_s = spec.solenoid_centre_yz
    y_min = y_s - spec.solenoid_radius_m - wall
    profile = CrossSection.batch_hull(
        [
            circle(r_can - _HOUSING_INSET_M, _SEG_CAN),
            circle(rho, 8, (y_min + rho, r_can - rho)),
            circle(
                spec.solenoid_radius_m + wall, _SEG_SOLENOID, (y_s, z_s + wall + _HOUSING_INSET_M)
            ),
        ]
    )
    return prism_x(profile, -_OVERLAP_M, spec.housing_length_m)


def _ears(spec: CoreSpec) -> list[Manifold]:
    """Mounting-flange ears with bolt holes at the housing's front face (+y side)."""
    x1 = spec.housing_length_m
    x0 = x1 - spec.flange_thickness_m
    half_width = spec.ear_width_m / 2.0
    ears = []
    for i, (angle, reach) in enumerate(zip(spec.ear_angles_deg, spec.ear_reach_m, strict=True)):
        tip = _polar(reach, angle)
        lug = stadium((0.0, 0.0), tip, half_width, _SEG_SMALL)
        lug = lug - circle(spec.ear_hole_radius_m, _SEG_SMALL, tip)
        if spec.broken_ear == i:
            lug = lug - _break_cut(spec, angle)
        ears.append(prism_x(lug, x0, x1))
    return ears


def _break_cut(spec: CoreSpec, angle_deg: float) -> CrossSection:
    """Half-plane (as a large square) that breaks an ear off 2 mm outside the can, slanted 20°."""
    size = 0.1
    square = CrossSection.square((size, size), center=True).rotate(angle_deg + 20.0)
    return square.translate(_polar(spec.can_radius_m + 0.002 + size / 2.0, angle_deg))


def _nose_and_pinion(spec: CoreSpec) -> list[Manifold]:
    """Tapered nose, drive shaft and the toothed pinion at +x."""
    x_nose = spec.housing_length_m
    x_shaft = x_nose + spec.nose_length_m
    x_pinion = x_shaft + spec.shaft_length_m
    nose = prism_x(
        circle(spec.nose_radius_m, _SEG_SOLENOID), x_nose - _OVERLAP_M, x_shaft, spec.nose_taper
    )
    shaft = prism_x(
        circle(spec.shaft_radius_m, _SEG_SMALL), x_shaft - _OVERLAP_M, x_pinion + _OVERLAP_M
    )
    pinion_outline = gear_profile(spec.pinion_teeth, spec.pinion_module_m)
    pinion = prism_x(pinion_outline, x_pinion, x_pinion + spec.pinion_length_m)
    return [nose, shaft, pinion]


def _solenoid(spec: CoreSpec) -> list[Manifold]:
    """Engagement relay: body, rear cap and two terminal studs (axial or sideways)."""
    centre = spec.solenoid_centre_yz
    r = spec.solenoid_radius_m
    x_front = spec.housing_length_m - spec.solenoid_inset_m
    x_body = x_front - spec.solenoid_length_m
    x_cap = x_body - spec.solenoid_cap_length_m
    body = prism_x(circle(r, _SEG_SOLENOID, centre), x_body, x_front)
    cap_radius = r - 0.0025
    cap = prism_x(circle(cap_radius, _SEG_SOLENOID, centre), x_cap, x_body + _OVERLAP_M)
    parts = [body, cap]
    if spec.stud_direction == "axial":
        for sign, radius in zip((-1.0, 1.0), spec.stud_radii_m, strict=True):
            pos = (centre[0] + sign * 0.42 * r, centre[1] + 0.1 * r)
            parts.append(
                prism_x(circle(radius, 12, pos), x_cap - spec.stud_length_m, x_cap + _OVERLAP_M)
            )
            parts.append(prism_x(circle(1.9 * radius, 6, pos), x_cap - 0.004, x_cap + _OVERLAP_M))
    else:
        x_mid = x_cap + spec.solenoid_cap_length_m / 2.0
        y_side = centre[0] - cap_radius + 0.002
        for sign, radius in zip((1.0, -1.0), spec.stud_radii_m, strict=True):
            z = centre[1] + sign * 0.3 * r
            parts.append(rod_y(radius, spec.stud_length_m, (x_mid, y_side, z), 12))
    return parts


def _rear(spec: CoreSpec) -> list[Manifold]:
    """Commutator end cap with bearing boss and two through-bolt heads (none if missing)."""
    if spec.missing_end_cap:
        return []
    x_can = -spec.can_length_m
    x_face = x_can - spec.end_cap_length_m
    cap = prism_x(circle(spec.end_cap_radius_m, _SEG_CAN), x_face, x_can + _OVERLAP_M)
    boss = prism_x(circle(spec.boss_radius_m, 32), x_face - spec.boss_length_m, x_face + _OVERLAP_M)
    parts = [cap, boss]
    bolt_circle = spec.end_cap_radius_m - 0.007
    for angle in (spec.bolt_angle_deg, spec.bolt_angle_deg + 180.0):
        head = circle(spec.bolt_head_radius_m, 6, _polar(bolt_circle, angle))
        parts.append(prism_x(head, x_face - spec.bolt_head_length_m, x_face + _OVERLAP_M))
    return parts


def _open_can_end(spec: CoreSpec) -> Manifold:
    """Recess left in the can when the end cap is missing (2.5 mm wall, 8 mm deep)."""
    x_can = -spec.can_length_m
    return prism_x(circle(spec.can_radius_m - 0.0025, _SEG_CAN), x_can - _OVERLAP_M, x_can + 0.008)


def _commutator(spec: CoreSpec) -> Manifold:
    """Exposed commutator sticking out of the open can end."""
    x_can = -spec.can_length_m
    return prism_x(circle(spec.boss_radius_m, 32), x_can - spec.boss_length_m, x_can + 0.009)


def _dent_sphere(spec: CoreSpec, dent: Dent) -> Manifold:
    """Sphere whose subtraction presses ``dent`` into its part."""
    if dent.part == "can":
        axis, radius = (0.0, 0.0), spec.can_radius_m
    else:
        axis, radius = spec.solenoid_centre_yz, spec.solenoid_radius_m
    y, z = _polar(radius + dent.radius_m - dent.depth_m, dent.angle_deg, axis)
    return sphere(dent.radius_m, (dent.x_m, y, z), 24)
