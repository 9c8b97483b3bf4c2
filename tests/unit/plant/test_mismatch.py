"""The mismatch plant (issue 29): structural differences the twin's model class cannot
represent, selectable by kind, reproducible, and as hidden as the in-class plant's values."""

from __future__ import annotations

import math
import pickle

import mujoco
import numpy as np
import pytest

from transfertwin._errors import InputError
from transfertwin.plant import EmulatedPlant, PlantRequest
from transfertwin.plant._mismatch import (
    MISMATCH_PARTS,
    PLANT_KINDS,
    SAG_BELTS,
    SAG_SEGMENTS,
    draw_mismatch_scene,
    mismatched_hulls,
    mismatched_inertia,
    without_parts,
)
from transfertwin.plant._mismatch_spec import slat_name
from transfertwin.plant._plant import (
    _fresh_system,
    _mismatch_object,
    _object_model,
    _scene_config,
    _system,
)
from transfertwin.plant._truth import draw_object, draw_scene
from transfertwin.sim import DockingError

REQUESTS = [PlantRequest("o3", "back", "both", 90), PlantRequest("o3", "front", "both", 30)]


def test_kind_is_chosen_by_name_and_in_class_stays_todays_plant() -> None:
    assert PLANT_KINDS == ("in-class", "mismatch", "bullet")
    with pytest.raises(InputError, match="--plant-kind"):
        EmulatedPlant(1, kind="pybullet")
    today, named = EmulatedPlant(2), EmulatedPlant(2, kind="in-class")
    assert today.kind == "in-class" and today.fingerprint(["o3"]) == named.fingerprint(["o3"])
    assert all(job.mismatch is None for job in today._jobs(REQUESTS))
    mismatch = EmulatedPlant(2, kind="mismatch")
    assert mismatch.fingerprint(["o3"]) != today.fingerprint(["o3"])
    jobs = mismatch._jobs(REQUESTS)
    assert all(job.mismatch is not None for job in jobs)
    # the in-class part of a mismatch plant is the in-class plant of the same seed
    assert [j.obj for j in jobs] == [j.obj for j in EmulatedPlant(2)._jobs(REQUESTS)]


def test_the_mismatch_plant_hides_its_values_like_the_in_class_one() -> None:
    plant = EmulatedPlant(3, kind="mismatch")
    public = {n for n in dir(plant) if not n.startswith("_")}
    assert public == {n for n in dir(EmulatedPlant(3)) if not n.startswith("_")}
    assert not hasattr(plant, "__dict__")
    assert repr(plant) == "EmulatedPlant(seed=3, kind='mismatch')"
    with pytest.raises(TypeError):
        pickle.dumps(plant)
    ms, m = draw_mismatch_scene(3), _mismatch_object(3, "o3")
    fp = plant.fingerprint(["o3"])
    assert len(fp) == 64 and str(ms.impratio) not in fp and str(ms.ripple) not in fp
    # the joints' and the sagging belts' values are hidden too, and enter the hash
    hidden = [*ms.sag[0], *(m.appendage_joint or ()), *(m.compliant or ())[1:]]
    assert hidden and not any(f"{v:.4g}" in fp for v in hidden)
    for part in ("appendage", "compliant", "sag"):
        assert EmulatedPlant(3, kind="mismatch", mismatch_off=(part,)).fingerprint(["o3"]) != fp
    assert not any(str(v) in repr(plant) + str(plant.weigh("o3")) for v in hidden)
    reading = plant.weigh("o3")  # the centre of mass moved by the mismatch, seen noisily
    shifted = np.asarray(EmulatedPlant(3).weigh("o3").com_m) + _mismatch_object(3, "o3").com_shift_m
    assert np.allclose(reading.com_m, shifted, atol=2e-4)


def test_the_structure_lies_outside_the_twins_model_class() -> None:
    obj = draw_object(1, "o3")
    model = _object_model(obj)
    m = _mismatch_object(1, "o3")
    hulls, features = mismatched_hulls(model.hulls, model.feature_hulls, m)
    core = len(model.hulls) - model.feature_hulls
    assert 2 <= len(m.bumps) <= 5 and 1 <= len(m.dents) <= 3
    assert len(hulls) == len(model.hulls) + len(m.bumps) + (m.appendage is not None)
    assert features == model.feature_hulls + (m.appendage is not None)
    dented = [not np.array_equal(a, b) for a, b in zip(hulls[:core], model.hulls, strict=False)]
    assert sum(dented) == len(m.dents)
    # knobs sit on the surface anywhere, not under a face's centre like a proxy's box
    centres = np.array([b[:3] for b in m.bumps])
    assert np.ptp(centres[:, 0]) > 0.01 or len(centres) == 1
    for seed in range(8):  # 3-D mass: a valid inertia tensor, not the in-class one
        inertia = _object_model(draw_object(seed, "o3")).mass.inertia_kg_m2
        new = mismatched_inertia(inertia, _mismatch_object(seed, "o3"))
        vals = np.linalg.eigvalsh(new)
        assert vals.min() > 0 and vals.max() <= vals.sum() - vals.max() + 1e-12
        assert not np.allclose(new, inertia)
    physics = _scene_config(draw_scene(1), obj, 0, draw_mismatch_scene(1)).physics
    assert (physics.solver, physics.cone, physics.condim) == ("PGS", "pyramidal", 4)
    assert physics.impratio > 1 and physics.solimp[2] >= 0.002
    assert _scene_config(draw_scene(1), obj).physics.solver == "Newton"


def test_the_mismatch_belts_ripple_and_the_right_belt_runs_off_the_left() -> None:
    obj, scene, ms = draw_object(1, "o3"), draw_scene(1), draw_mismatch_scene(1)
    system = _system(obj, scene, 0, (_mismatch_object(1, "o3"), ms))
    system.tm.set_belt_speed("left", 0.1)
    system.tm.set_belt_speed("right", 0.1)
    left, right = system.tm._belt_rows["left"][0][0], system.tm._belt_rows["right"][0][0]
    speeds = []
    for _ in range(6):
        system.clock.wait(0.05)
        speeds.append(system.model.geom_surfacevel[[left, right], 0].copy())
    speeds = np.array(speeds)
    assert system.tm.belt_speed("left") == 0.1  # the command is what a log shows
    assert np.ptp(speeds[:, 0]) > 0.002  # ripple over time
    ratio = speeds[:, 1] / speeds[:, 0]
    assert np.allclose(ratio, 1 + ms.right_belt_skew[0], atol=1e-3)


def test_same_seed_same_mismatch_rows() -> None:
    a = EmulatedPlant(4, kind="mismatch").run(REQUESTS[:1])
    b = EmulatedPlant(4, kind="mismatch").run(REQUESTS[:1])
    assert a == b


def test_each_mismatch_part_switches_off_alone() -> None:
    with pytest.raises(InputError, match="switch off"):
        EmulatedPlant(1, kind="mismatch", mismatch_off=("friction",))
    with pytest.raises(InputError, match="switch off"):
        EmulatedPlant(1, mismatch_off=("shape",))  # only a mismatch plant has parts
    full = EmulatedPlant(1, kind="mismatch")._jobs(REQUESTS)[0].mismatch
    assert MISMATCH_PARTS == ("shape", "mass", "belts", "contact", "appendage", "compliant", "sag")
    for part in MISMATCH_PARTS:
        plant = EmulatedPlant(1, kind="mismatch", mismatch_off=(part,))
        obj, scene = plant._jobs(REQUESTS)[0].mismatch
        assert (obj, scene) != full and part in repr(plant)
        assert (obj.bumps == ()) == (part == "shape")
        assert (obj.inertia_scale == (1.0, 1.0, 1.0)) == (part == "mass")
        assert (scene.ripple == 0.0) == (part == "belts")
        physics = _scene_config(draw_scene(1), draw_object(1, "o3"), 0, scene).physics
        assert (physics.solver == "Newton") == (part == "contact")
        assert (obj.appendage is None and obj.appendage_joint is None) == (part == "appendage")
        assert (obj.compliant is None) == (part == "compliant")
        assert (scene.sag == ()) == (part == "sag")
    off = EmulatedPlant(1, kind="mismatch", mismatch_off=MISMATCH_PARTS)
    assert off.weigh("o3") == EmulatedPlant(1).weigh("o3")
    # with every part off, the plant's compiled system has the in-class plant's structure
    obj, scene = off._jobs(REQUESTS)[0].mismatch
    bare = _fresh_system(draw_object(1, "o3"), draw_scene(1), 0, (obj, scene)).model
    in_class = _fresh_system(draw_object(1, "o3"), draw_scene(1)).model
    assert (bare.nbody, bare.njnt, bare.ngeom) == (in_class.nbody, in_class.njnt, in_class.ngeom)


def _settled(mismatch, face: str = "front", seconds: float = 1.0):
    """Plant system of o3 (seed 1) with `mismatch`, the object settled mid-TM, belts still."""
    system = _fresh_system(draw_object(1, "o3"), draw_scene(1), 0, mismatch)
    system.reset(DockingError(0.0, 0.0, 0.0))
    system.place(face, 0.5, -0.325, 0.0)
    system.clock.wait(seconds)
    return system


def _joint_q(system, name: str) -> np.ndarray:
    joint = system.model.joint(name)
    size = 4 if joint.type[0] == mujoco.mjtJoint.mjJNT_BALL else 1
    return system.data.qpos[joint.qposadr[0] : joint.qposadr[0] + size].copy()


def test_the_jointed_parts_compile_with_their_drawn_springs() -> None:
    m, ms = _mismatch_object(1, "o3"), draw_mismatch_scene(1)
    assert m.appendage is not None and m.appendage_joint is not None and m.compliant is not None
    system = _fresh_system(draw_object(1, "o3"), draw_scene(1), 0, (m, ms))
    model = system.model
    k, _, ref = m.appendage_joint
    bend, side, fold = (model.joint(f"object_part{n}_joint") for n in range(3))
    assert bend.type[0] == side.type[0] == mujoco.mjtJoint.mjJNT_HINGE
    assert fold.type[0] == mujoco.mjtJoint.mjJNT_SLIDE and fold.limited[0]
    assert bend.stiffness[0] == pytest.approx(k)
    assert model.qpos_spring[bend.qposadr[0]] == pytest.approx(ref)  # radians
    assert side.stiffness[0] == pytest.approx(k * (m.appendage[7] / m.appendage[8]) ** 2)
    assert fold.range[0] == pytest.approx(-m.appendage[6])
    ball = model.joint("object_part3_joint")
    assert ball.type[0] == mujoco.mjtJoint.mjJNT_BALL
    assert ball.stiffness[0] == pytest.approx(m.compliant[4])
    assert np.allclose(model.body("object_part3").pos, m.compliant[1:4])  # the second body
    # the parts' hulls left the core body; the object weighs what the in-class one does
    core = model.body("object").id
    parts = [model.body(f"object_part{n}").id for n in (0, 3)]
    for part, hull in zip(parts, (28, 26), strict=True):  # appendage last, feature 23 + 3 knobs
        assert model.geom_bodyid[model.geom(f"object_hull_{hull}").id] == part
    in_class = _fresh_system(draw_object(1, "o3"), draw_scene(1), 0, without_parts(
        m, ms, frozenset({"appendage", "compliant"})))  # fmt: skip
    assert model.body_mass[[core, *parts]].sum() == pytest.approx(
        in_class.model.body_mass[in_class.model.body("object").id], rel=1e-12)
    assert model.body_mass[parts].min() > 0


def test_the_belt_decks_sag_along_their_drawn_profile() -> None:
    ms = draw_mismatch_scene(1)
    system = _fresh_system(draw_object(1, "o3"), draw_scene(1), 0, (_mismatch_object(1, "o3"), ms))
    model = system.model
    u = np.linspace(0.0, 1.0, SAG_SEGMENTS + 1)
    for (unit, belt), (depth, stiffness, _) in zip(SAG_BELTS, ms.sag, strict=True):
        names = [slat_name(unit, belt, i) for i in range(SAG_SEGMENTS)]
        bodies = [model.geom(n).bodyid[0] for n in names]
        profile = -depth * np.sin(np.pi * u)
        assert np.allclose([model.body_pos[b][2] for b in bodies],
                           (profile[1:] + profile[:-1]) / 2)  # fmt: skip
        assert min(model.body_pos[b][2] for b in bodies) < -0.5 * depth
        assert all(model.body_gravcomp[b] == 1.0 for b in bodies)
        joints = [model.joint(f"{n}_joint") for n in names]
        assert all(j.stiffness[0] == pytest.approx(stiffness) for j in joints)
    # the slats run with the belt
    system.tm.set_belt_speed("left", 0.1)
    rows = [model.geom(slat_name("tm", "left", i)).id for i in range(SAG_SEGMENTS)]
    assert np.all(model.geom_surfacevel[rows, 0] == model.geom_surfacevel[rows[0], 0])
    assert model.geom_surfacevel[rows[0], 0] != 0


def test_the_new_parts_change_a_resting_state() -> None:
    m, ms = _mismatch_object(1, "o3"), draw_mismatch_scene(1)
    full = _settled((m, ms))
    flat = _settled(without_parts(m, ms, frozenset({"sag"})))
    # the load presses the slats down and the object rests lower than on flat decks
    slats = [_joint_q(full, f"{slat_name(u, b, i)}_joint")[0] for u, b in SAG_BELTS[:2]
             for i in range(SAG_SEGMENTS)]  # fmt: skip
    assert min(slats) < -5e-4
    assert full.data.xipos[full._body][2] < flat.data.xipos[flat._body][2] - 5e-4
    # the appendage flexes against the belt, the compliant part gives way
    assert abs(_joint_q(full, "object_part0_joint")[0] - m.appendage_joint[2]) > 0.1
    w = _joint_q(full, "object_part3_joint")[0]
    assert 2 * math.acos(min(1.0, abs(w))) > 0.02
    assert np.array_equal(_settled((m, ms)).data.qpos, full.data.qpos)  # same bits
