"""`mass_properties` against closed-form values of a box and a cylinder."""

from __future__ import annotations

import math

import numpy as np
import pytest
import trimesh

from transfertwin import InputError
from transfertwin.objects import DEFAULT_DENSITY_KG_M3, MassProperties, mass_properties


def test_box_mass_com_and_inertia_match_closed_form() -> None:
    a, b, c = 0.10, 0.20, 0.30
    mass = 6.0
    centre = np.array([0.5, -0.2, 0.1])
    box = trimesh.creation.box(extents=(a, b, c))
    box.apply_translation(centre)
    props = mass_properties(box, mass_kg=mass)
    expected = mass / 12.0 * np.diag([b * b + c * c, a * a + c * c, a * a + b * b])
    assert props.mass_kg == pytest.approx(mass)
    np.testing.assert_allclose(props.com_m, centre, atol=1e-12)
    np.testing.assert_allclose(props.inertia_kg_m2, expected, rtol=1e-9, atol=1e-15)


def test_rotated_box_inertia_is_rotated_closed_form() -> None:
    a, b, c = 0.10, 0.20, 0.30
    density = 2700.0
    rotation = trimesh.transformations.rotation_matrix(math.radians(30.0), [0, 0, 1])
    box = trimesh.creation.box(extents=(a, b, c))
    box.apply_transform(rotation)
    props = mass_properties(box, density_kg_m3=density)
    mass = density * a * b * c
    body = mass / 12.0 * np.diag([b * b + c * c, a * a + c * c, a * a + b * b])
    r = rotation[:3, :3]
    np.testing.assert_allclose(props.inertia_kg_m2, r @ body @ r.T, rtol=1e-9, atol=1e-15)


def test_cylinder_mass_and_inertia_match_closed_form() -> None:
    radius, height, density = 0.04, 0.15, 7850.0
    cylinder = trimesh.creation.cylinder(radius=radius, height=height, sections=512)
    props = mass_properties(cylinder, density_kg_m3=density)
    mass = density * math.pi * radius**2 * height
    i_axis = mass * radius**2 / 2.0
    i_transverse = mass * (3.0 * radius**2 + height**2) / 12.0
    # a 512-gon has 0.003 % less area than the circle
    assert props.mass_kg == pytest.approx(mass, rel=1e-4)
    np.testing.assert_allclose(
        np.diag(props.inertia_kg_m2), [i_transverse, i_transverse, i_axis], rtol=1e-4
    )
    off_diagonal = props.inertia_kg_m2 - np.diag(np.diag(props.inertia_kg_m2))
    assert np.abs(off_diagonal).max() < 1e-9 * i_axis
    np.testing.assert_allclose(props.com_m, 0.0, atol=1e-12)


def test_default_density_is_used_without_mass_or_density() -> None:
    box = trimesh.creation.box(extents=(0.1, 0.1, 0.1))
    assert mass_properties(box).mass_kg == pytest.approx(DEFAULT_DENSITY_KG_M3 * 1e-3)


def test_default_density_is_3500() -> None:
    assert DEFAULT_DENSITY_KG_M3 == 3500.0


def test_mass_properties_arrays_are_read_only() -> None:
    props = mass_properties(trimesh.creation.box(extents=(0.1, 0.1, 0.1)))
    assert isinstance(props, MassProperties)
    with pytest.raises(ValueError):
        props.com_m[0] = 1.0
    with pytest.raises(ValueError):
        props.inertia_kg_m2[0, 0] = 1.0


def test_mass_and_density_together_are_rejected() -> None:
    box = trimesh.creation.box(extents=(0.1, 0.1, 0.1))
    with pytest.raises(InputError, match="not both"):
        mass_properties(box, mass_kg=1.0, density_kg_m3=1000.0)


@pytest.mark.parametrize(
    "kwargs",
    [
        {"mass_kg": 0.0},
        {"mass_kg": -1.0},
        {"mass_kg": math.nan},
        {"density_kg_m3": 0.0},
        {"density_kg_m3": -2.0},
        {"density_kg_m3": math.inf},
        {"mass_kg": "3"},
    ],
)
def test_non_positive_or_non_finite_mass_or_density_is_rejected(kwargs: dict) -> None:
    box = trimesh.creation.box(extents=(0.1, 0.1, 0.1))
    with pytest.raises(InputError, match="must be a finite number > 0"):
        mass_properties(box, **kwargs)


def test_open_mesh_is_rejected() -> None:
    box = trimesh.creation.box(extents=(0.1, 0.1, 0.1))
    open_box = trimesh.Trimesh(box.vertices, box.faces[2:], process=False)
    with pytest.raises(InputError, match="watertight"):
        mass_properties(open_box)


def test_inside_out_mesh_is_rejected() -> None:
    box = trimesh.creation.box(extents=(0.1, 0.1, 0.1))
    inverted = trimesh.Trimesh(box.vertices, box.faces[:, ::-1], process=False)
    with pytest.raises(InputError, match="positive volume"):
        mass_properties(inverted)
