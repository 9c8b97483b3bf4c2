"""The state readout (Eq. 5.4 without f, c, t) against a direct computation from every hull
vertex, on a built-in core tumbling across the gap, and the belts' surface velocities."""

from __future__ import annotations

import math

import numpy as np
import pytest

from transfertwin.objects import load_object
from transfertwin.sim import DockingError, SceneConfig, VirtualTransferSystem


def _core_system() -> VirtualTransferSystem:
    obj = load_object("o18")
    m = obj.mass
    system = VirtualTransferSystem(obj.hulls, m.mass_kg, m.com_m, m.inertia_kg_m2, SceneConfig())
    system.reset(DockingError.from_mm_deg(-8.0, 3.0, 1.5))
    return system


def _direct(system: VirtualTransferSystem, com: np.ndarray) -> np.ndarray:
    """(a, x, y, z, s_x, s_y, s_z, θ) from all hull vertices, written out plainly."""
    pos, rot = system.object_pose()
    pts = system._verts @ rot.T + pos  # every vertex of every hull, in F_T
    lo, hi = pts.min(axis=0), pts.max(axis=0)
    com_t = rot @ com + pos
    a = system.possessing_unit(com_t[:2])
    theta = math.atan2(rot[1, 0], rot[0, 0])
    return np.array([a, *(0.5 * (lo + hi)), *(0.5 * (hi - lo)), theta])


def test_observe_is_the_aabb_of_all_hull_vertices_com_side_and_yaw_while_tumbling() -> None:
    system = _core_system()
    com = load_object("o18").mass.com_m
    system.place("front", math.radians(35.0), -0.25, 0.02)
    for hal in (system.tm, system.tu):
        for belt in ("left", "right"):
            hal.set_belt_speed(belt, 0.15)
    seen_units = set()
    for _ in range(60):  # 4 s: across the gap, turning and tipping on the way
        system.clock.wait(1 / 15)
        obs = system.observe()
        np.testing.assert_allclose(obs, _direct(system, com), rtol=0, atol=1e-12)
        seen_units.add(int(obs[0]))
    assert seen_units == {0, 1}  # both sides of the gap were read


def test_belt_speed_sets_deck_and_pulley_surface_velocities() -> None:
    system = _core_system()
    system.tu.set_belt_speed("left", 0.2)
    sv = system.model.geom_surfacevel
    rows, axles = system.tu._belt_rows["left"]
    deck, start, end = rows
    np.testing.assert_array_equal(sv[deck], [0.2, 0, 0, 0, 0, 0])
    r = SceneConfig().layout.pulley_radius_m
    for gid, axle in zip((start, end), axles, strict=True):
        np.testing.assert_array_equal(sv[gid, :3], 0.0)
        np.testing.assert_allclose(sv[gid, 3:], 0.2 / r * axle)
        assert np.linalg.norm(axle) == pytest.approx(1.0)
    system.tu.set_belt_speed("left", 0.0)
    assert not sv[list(rows)].any()
    assert system.tu.belt_speed("left") == 0.0
