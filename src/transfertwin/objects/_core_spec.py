"""Specification of a procedural starter-motor core (dimensions, mass, wear).

A `CoreSpec` is drawn by `transfertwin.objects._core_draw.core_spec` from a
numpy `Generator` seeded from the core index. Dimensions follow passenger-car
starters: yoke can Ø 70–95 mm, engagement relay (solenoid) Ø 40–55 mm, overall
length about 185–250 mm, mass 2.2–4.9 kg. All lengths are in metres, angles in
degrees, in the build frame: x along the motor axis towards the pinion, the
can/housing junction at x = 0, the can axis on the x axis, the solenoid at -y
(see `transfertwin.objects._core_builder`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Literal

__all__ = ["BUILTIN_COUNT", "CoreSpec", "Dent"]

BUILTIN_COUNT = 37
"""Number of built-in cores o1..o37 (the study's set O, Eq. 5.3)."""


@dataclass(frozen=True)
class Dent:
    """A dent: a sphere of radius ``radius_m`` pressed ``depth_m`` into a part.

    Attributes:
        part: ``"can"`` or ``"solenoid"``.
        x_m: Axial position of the dent centre (build frame, m).
        angle_deg: Position around the part's axis, from +y towards +z (deg).
        radius_m: Radius of the pressing sphere (m).
        depth_m: Depth of the dent below the surface (m).
    """

    part: Literal["can", "solenoid"]
    x_m: float
    angle_deg: float
    radius_m: float
    depth_m: float


@dataclass(frozen=True)
class CoreSpec:
    """Geometry, mass and wear of one procedural starter-motor core.

    Lengths in metres (suffix ``_m``), angles in degrees (``_deg``), build frame
    (see module docstring). Parts, from -x to +x: bearing boss and end cap
    with two through-bolt heads (``end_cap_*``, ``boss_*``, ``bolt_*``), yoke
    can (``can_*``), D-shaped drive-end housing (``housing_*``) with the
    mounting-flange ears at its front face (``flange_thickness_m``, ``ear_*``),
    tapered nose (``nose_*``, ``nose_taper`` = end/start radius), drive shaft
    and pinion (``shaft_*``, ``pinion_*``, tip radius m (z + 2) / 2). The
    engagement relay (``solenoid_*``) lies beside the can at -y, its front
    ``solenoid_inset_m`` inside the housing, with a rear cap and two terminal
    studs pointing -x (``"axial"``) or -y (``"sideways"``).

    Ear angles are measured in the (y, z) plane from +y towards +z; all ears
    lie on the +y side, away from the solenoid, and stay inside the band
    |z| < can radius - 1.5 mm so that they never touch the ground on either
    face. Wear: ``dents``, ``broken_ear`` (index into the ears, broken 2 mm
    outside the can) and ``missing_end_cap`` (open can end, commutator
    exposed). ``mass_kg`` is the core's mass (uniform density over the mesh).
    """

    index: int
    can_radius_m: float
    can_length_m: float
    end_cap_radius_m: float
    end_cap_length_m: float
    boss_radius_m: float
    boss_length_m: float
    bolt_head_radius_m: float
    bolt_head_length_m: float
    bolt_angle_deg: float
    housing_length_m: float
    housing_corner_radius_m: float
    housing_wall_m: float
    flange_thickness_m: float
    ear_angles_deg: tuple[float, ...]
    ear_reach_m: tuple[float, ...]
    ear_width_m: float
    ear_hole_radius_m: float
    nose_length_m: float
    nose_radius_m: float
    nose_taper: float
    shaft_radius_m: float
    shaft_length_m: float
    pinion_teeth: int
    pinion_module_m: float
    pinion_length_m: float
    solenoid_radius_m: float
    solenoid_length_m: float
    solenoid_gap_m: float
    solenoid_inset_m: float
    solenoid_cap_length_m: float
    stud_direction: Literal["axial", "sideways"]
    stud_radii_m: tuple[float, ...]
    stud_length_m: float
    dents: tuple[Dent, ...]
    broken_ear: int | None
    missing_end_cap: bool
    mass_kg: float

    @property
    def object_id(self) -> str:
        """Object id ``"o<index>"``."""
        return f"o{self.index}"

    @property
    def solenoid_centre_yz(self) -> tuple[float, float]:
        """Solenoid axis (y, z) in m: beside the can at -y, its bottom at z = -can radius."""
        z = -(self.can_radius_m - self.solenoid_radius_m)
        distance = self.can_radius_m + self.solenoid_radius_m + self.solenoid_gap_m
        return (-math.sqrt(distance**2 - z**2), z)

    @property
    def pinion_tip_radius_m(self) -> float:
        """Tip radius of the pinion, m (z + 2) / 2, in m."""
        return self.pinion_module_m * (self.pinion_teeth + 2) / 2.0

    @property
    def rear_length_m(self) -> float:
        """Axial length behind the can: end cap + bearing boss, or the exposed commutator."""
        if self.missing_end_cap:
            return self.boss_length_m
        return self.end_cap_length_m + self.boss_length_m

    @property
    def front_length_m(self) -> float:
        """Axial length in front of the can: housing + nose + shaft + pinion, in m."""
        return (
            self.housing_length_m + self.nose_length_m + self.shaft_length_m + self.pinion_length_m
        )

    @property
    def overall_length_m(self) -> float:
        """Nominal overall length along x in m."""
        return self.rear_length_m + self.can_length_m + self.front_length_m

    @property
    def wear(self) -> tuple[str, ...]:
        """Wear flags: ``"dent"``, ``"broken_ear"``, ``"missing_end_cap"`` (empty if unworn)."""
        flags = []
        if self.dents:
            flags.append("dent")
        if self.broken_ear is not None:
            flags.append("broken_ear")
        if self.missing_end_cap:
            flags.append("missing_end_cap")
        return tuple(flags)
