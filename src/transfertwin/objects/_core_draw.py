"""Drawing a `CoreSpec` from its index (deterministic, seeded numpy `Generator`).

``core_spec(i)`` seeds PCG64 from ``SeedSequence([_SEED_BASE, i])``, so it is the
same on every machine. Dimensions are drawn uniformly in ranges of
passenger-car starters, rounded to 0.1 mm (0.1°); the can length makes the
overall length hit a drawn target; the mass is an effective density times an
estimated solid volume.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from transfertwin._errors import InputError
from transfertwin.objects._core_spec import CoreSpec, Dent

__all__ = ["core_spec"]

_SEED_BASE = 0x57A27E2  # "starter"; fixed forever: changing it changes every core
_MASS_RANGE_KG = (2.2, 4.9)
_DENSITY_RANGE_KG_M3 = (2800.0, 3600.0)
_LENGTH_RANGE_M = (0.185, 0.240)
_CAN_LENGTH_RANGE_M = (0.060, 0.120)


def core_spec(index: int) -> CoreSpec:
    """Draw the specification of core ``index`` (deterministic).

    Args:
        index: Core number, >= 1; ``1..37`` are the built-in cores o1..o37.

    Returns:
        The specification.

    Raises:
        InputError: If ``index`` is not an integer >= 1.
    """
    if isinstance(index, bool) or not isinstance(index, (int, np.integer)) or index < 1:
        raise InputError(f"core index must be an integer >= 1, got {index!r}")
    rng = np.random.default_rng(np.random.SeedSequence([_SEED_BASE, int(index)]))
    fields = _draw_fields(rng)
    fields.update(_draw_damage(rng, fields))
    fields["can_length_m"] = _can_length(rng, fields)
    fields["solenoid_length_m"] = _solenoid_length(rng, fields)
    fields["dents"] = _draw_dents(rng, fields)
    fields["mass_kg"] = _mass(rng, fields)
    return CoreSpec(index=int(index), **fields)


def _u(rng: np.random.Generator, lo: float, hi: float, digits: int = 4) -> float:
    """Uniform draw rounded to ``digits`` decimals (0.1 mm for metres)."""
    return round(float(rng.uniform(lo, hi)), digits)


def _draw_fields(rng: np.random.Generator) -> dict[str, Any]:
    """Draw the shape fields except the can and solenoid lengths."""
    can_radius = _u(rng, 0.035, 0.0475)
    solenoid_radius = _u(rng, 0.020, min(0.0275, can_radius - 0.006))
    ear_width = _u(rng, 0.016, 0.022)
    angles, reach = _ears(rng, can_radius, ear_width)
    nose_radius = _u(rng, 0.62, 0.78) * can_radius
    return {
        "can_radius_m": can_radius,
        "end_cap_radius_m": round(can_radius - _u(rng, 0.0015, 0.004), 4),
        "end_cap_length_m": _u(rng, 0.012, 0.022),
        "boss_radius_m": round(_u(rng, 0.22, 0.32) * can_radius, 4),
        "boss_length_m": _u(rng, 0.005, 0.010),
        "bolt_head_radius_m": _u(rng, 0.005, 0.0065),
        "bolt_head_length_m": _u(rng, 0.004, 0.006),
        "bolt_angle_deg": _u(rng, 60.0, 120.0, 1),
        "housing_length_m": _u(rng, 0.024, 0.036),
        "housing_corner_radius_m": _u(rng, 0.006, 0.010),
        "housing_wall_m": _u(rng, 0.002, 0.005),
        "flange_thickness_m": _u(rng, 0.008, 0.012),
        "ear_angles_deg": angles,
        "ear_reach_m": reach,
        "ear_width_m": ear_width,
        "ear_hole_radius_m": _u(rng, 0.0045, 0.006),
        "nose_length_m": _u(rng, 0.018, 0.032),
        "nose_radius_m": round(nose_radius, 4),
        "nose_taper": _u(rng, 0.78, 0.92, 3),
        "shaft_radius_m": _u(rng, 0.0045, 0.006),
        "shaft_length_m": _u(rng, 0.003, 0.008),
        "pinion_teeth": int(rng.integers(9, 13)),
        "pinion_module_m": _u(rng, 0.0021, 0.0026, 5),
        "pinion_length_m": _u(rng, 0.014, 0.022),
        "solenoid_radius_m": solenoid_radius,
        "solenoid_gap_m": _u(rng, -0.003, 0.002),
        "solenoid_inset_m": _u(rng, 0.006, 0.014),
        "solenoid_cap_length_m": _u(rng, 0.008, 0.014),
        "stud_direction": "axial" if rng.random() < 0.6 else "sideways",
        "stud_radii_m": tuple(_u(rng, lo, hi) for lo, hi in ((0.0035, 0.0045), (0.0022, 0.003))),
        "stud_length_m": _u(rng, 0.010, 0.016),
    }


def _ears(
    rng: np.random.Generator, can_radius: float, ear_width: float
) -> tuple[tuple[float, ...], tuple[float, ...]]:
    """Ear angles (deg) and reaches (m), kept inside the band |z| <= can radius - 1.5 mm."""
    if rng.random() < 0.35:
        spread = float(rng.uniform(28.0, 36.0))
        angles = [float(rng.uniform(-5.0, 5.0)), spread, -spread - float(rng.uniform(0.0, 4.0))]
    else:
        angles = [float(rng.uniform(12.0, 30.0)), -float(rng.uniform(12.0, 30.0))]
    band = can_radius - 0.0015 - ear_width / 2.0
    reaches = []
    for i, angle in enumerate(angles):
        reach = float(rng.uniform(can_radius + 0.004, can_radius + 0.012))
        sin_a = abs(math.sin(math.radians(angle)))
        if reach * sin_a > band:
            reach = max(band / sin_a, can_radius + 0.002)
            angles[i] = math.copysign(math.degrees(math.asin(band / reach)), angle)
        reaches.append(round(reach, 4))
    return tuple(round(a, 1) for a in angles), tuple(reaches)


def _draw_damage(rng: np.random.Generator, fields: dict[str, Any]) -> dict[str, Any]:
    """Draw a broken ear (15 %) and a missing end cap (12 %)."""
    broken = int(rng.integers(len(fields["ear_angles_deg"]))) if rng.random() < 0.15 else None
    return {"broken_ear": broken, "missing_end_cap": bool(rng.random() < 0.12)}


def _draw_dents(rng: np.random.Generator, fields: dict[str, Any]) -> tuple[Dent, ...]:
    """Draw 1–2 dents on the can or the solenoid for 30 % of the cores."""
    if rng.random() >= 0.3:
        return ()
    dents = []
    for _ in range(int(rng.integers(1, 3))):
        on_can = rng.random() < 0.7
        if on_can:
            x_range = (-0.85 * fields["can_length_m"], -0.15 * fields["can_length_m"])
        else:
            front = fields["housing_length_m"] - fields["solenoid_inset_m"]
            x_range = (
                front - 0.8 * fields["solenoid_length_m"],
                front - 0.2 * fields["solenoid_length_m"],
            )
        dents.append(
            Dent(
                part="can" if on_can else "solenoid",
                x_m=_u(rng, *x_range),
                angle_deg=_u(rng, -180.0, 180.0, 1),
                radius_m=_u(rng, 0.008, 0.016),
                depth_m=_u(rng, 0.0015, 0.004),
            )
        )
    return tuple(dents)


def _can_length(rng: np.random.Generator, fields: dict[str, Any]) -> float:
    """Can length that makes the overall length hit a drawn target."""
    target = float(rng.uniform(*_LENGTH_RANGE_M))
    rear = fields["boss_length_m"] + (
        0.0 if fields["missing_end_cap"] else fields["end_cap_length_m"]
    )
    front = sum(
        fields[k]
        for k in ("housing_length_m", "nose_length_m", "shaft_length_m", "pinion_length_m")
    )
    return round(min(max(target - rear - front, _CAN_LENGTH_RANGE_M[0]), _CAN_LENGTH_RANGE_M[1]), 4)


def _solenoid_length(rng: np.random.Generator, fields: dict[str, Any]) -> float:
    """Solenoid body length, not reaching behind the can."""
    room = fields["can_length_m"] + fields["housing_length_m"] - fields["solenoid_inset_m"] - 0.005
    return round(min(float(rng.uniform(0.070, 0.100)), room), 4)


def _mass(rng: np.random.Generator, fields: dict[str, Any]) -> float:
    """Mass in kg: an effective density times the estimated solid volume, clamped to 2.2–4.9 kg."""
    volume = _estimated_volume_m3(fields)
    density = float(rng.uniform(*_DENSITY_RANGE_KG_M3))
    mass = min(max(density * volume, _MASS_RANGE_KG[0]), _MASS_RANGE_KG[1])
    return round(mass, 3)


def _estimated_volume_m3(fields: dict[str, Any]) -> float:
    """Rough solid volume (m^3) from the main primitives; overlaps are ignored."""
    r_can, r_sol = fields["can_radius_m"], fields["solenoid_radius_m"]
    can = math.pi * r_can**2 * fields["can_length_m"]
    solenoid = math.pi * r_sol**2 * fields["solenoid_length_m"]
    width = r_can + r_sol + fields["solenoid_gap_m"] + r_sol
    housing = (math.pi * r_can**2 / 2.0 + 2.0 * r_can * width) * fields["housing_length_m"]
    r_nose = fields["nose_radius_m"]
    nose = math.pi * r_nose**2 * fields["nose_length_m"] * (1 + fields["nose_taper"]) / 2.0
    rear = (
        0.0
        if fields["missing_end_cap"]
        else math.pi * fields["end_cap_radius_m"] ** 2 * (fields["end_cap_length_m"])
    )
    return can + solenoid + housing + nose + rear
