"""`core_spec` / `generate_core`: determinism, variety, passenger-car starter ranges."""

from __future__ import annotations

import hashlib

import numpy as np
import pytest

from transfertwin import InputError
from transfertwin.objects import BUILTIN_COUNT, CoreSpec, core_spec, generate_core
from transfertwin.objects._cores import core_stl_bytes

SPECS = [core_spec(i) for i in range(1, BUILTIN_COUNT + 1)]


def test_core_spec_is_deterministic() -> None:
    assert core_spec(7) == core_spec(7)
    assert core_spec(np.int64(7)) == core_spec(7)


def test_all_builtin_specs_differ() -> None:
    assert len(set(SPECS)) == BUILTIN_COUNT


@pytest.mark.parametrize("bad", [0, -3, 1.5, True, "3", None])
def test_core_spec_rejects_non_positive_or_non_integer_index(bad: object) -> None:
    with pytest.raises(InputError, match="core index"):
        core_spec(bad)


def test_generate_core_is_bit_for_bit_repeatable() -> None:
    first = core_stl_bytes(5)
    assert core_stl_bytes(5) == first
    assert hashlib.sha256(first).hexdigest() != hashlib.sha256(core_stl_bytes(6)).hexdigest()


def test_generate_core_is_a_closed_volume_with_origin_at_centre_of_mass() -> None:
    mesh = generate_core(11)
    assert mesh.is_watertight and mesh.is_volume
    np.testing.assert_allclose(mesh.center_mass, 0.0, atol=1e-6)


@pytest.mark.parametrize(
    ("field", "lo", "hi"),
    [
        ("can_radius_m", 0.035, 0.0475),  # can Ø 70–95 mm
        ("solenoid_radius_m", 0.020, 0.0275),  # solenoid Ø 40–55 mm
        ("mass_kg", 2.0, 5.0),
        ("overall_length_m", 0.18, 0.26),
        ("pinion_tip_radius_m", 0.010, 0.020),
    ],
)
def test_spec_dimensions_are_those_of_passenger_car_starters(
    field: str, lo: float, hi: float
) -> None:
    values = np.array([getattr(spec, field) for spec in SPECS])
    assert values.min() >= lo
    assert values.max() <= hi
    assert len(np.unique(values)) > BUILTIN_COUNT // 2  # varied, not constant


def test_solenoid_is_smaller_than_the_can_and_beside_it_at_minus_y() -> None:
    for spec in SPECS:
        y, z = spec.solenoid_centre_yz
        assert spec.solenoid_radius_m < spec.can_radius_m
        assert y < -spec.can_radius_m
        assert z - spec.solenoid_radius_m == pytest.approx(-spec.can_radius_m, abs=1e-12)


def test_ears_two_or_three_and_their_layout_varies() -> None:
    counts = {len(spec.ear_angles_deg) for spec in SPECS}
    assert counts == {2, 3}
    assert len({spec.ear_angles_deg for spec in SPECS}) == BUILTIN_COUNT


def test_at_least_eight_cores_are_worn_with_each_kind_of_wear() -> None:
    worn = [spec for spec in SPECS if spec.wear]
    assert len(worn) >= 8
    kinds = {flag for spec in worn for flag in spec.wear}
    assert kinds == {"dent", "broken_ear", "missing_end_cap"}


def test_wear_flags_follow_the_fields() -> None:
    for spec in SPECS:
        assert ("dent" in spec.wear) == bool(spec.dents)
        assert ("broken_ear" in spec.wear) == (spec.broken_ear is not None)
        assert ("missing_end_cap" in spec.wear) == spec.missing_end_cap


def test_spec_is_frozen() -> None:
    spec: CoreSpec = SPECS[0]
    with pytest.raises(AttributeError):
        spec.mass_kg = 1.0  # type: ignore[misc]
