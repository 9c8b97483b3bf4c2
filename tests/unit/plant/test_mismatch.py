"""The mismatch plant (issue 29): structural differences the twin's model class cannot
represent, selectable by kind, reproducible, and as hidden as the in-class plant's values."""

from __future__ import annotations

import pickle

import numpy as np
import pytest

from transfertwin._errors import InputError
from transfertwin.plant import EmulatedPlant, PlantRequest
from transfertwin.plant._mismatch import (
    PLANT_KINDS,
    draw_mismatch_scene,
    mismatched_hulls,
    mismatched_inertia,
)
from transfertwin.plant._plant import _mismatch_object, _object_model, _scene_config, _system
from transfertwin.plant._truth import draw_object, draw_scene

REQUESTS = [PlantRequest("o3", "back", "both", 90), PlantRequest("o3", "front", "both", 30)]


def test_kind_is_chosen_by_name_and_in_class_stays_todays_plant() -> None:
    assert PLANT_KINDS == ("in-class", "mismatch")
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
    ms = draw_mismatch_scene(3)
    fp = plant.fingerprint(["o3"])
    assert len(fp) == 64 and str(ms.impratio) not in fp and str(ms.ripple) not in fp
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
    a = EmulatedPlant(4, kind="mismatch").run(REQUESTS)
    b = EmulatedPlant(4, kind="mismatch").run(REQUESTS)
    assert a == b


def test_each_mismatch_part_switches_off_alone() -> None:
    with pytest.raises(InputError, match="switch off"):
        EmulatedPlant(1, kind="mismatch", mismatch_off=("friction",))
    with pytest.raises(InputError, match="switch off"):
        EmulatedPlant(1, mismatch_off=("shape",))  # only a mismatch plant has parts
    full = EmulatedPlant(1, kind="mismatch")._jobs(REQUESTS)[0].mismatch
    for part in ("shape", "mass", "belts", "contact"):
        plant = EmulatedPlant(1, kind="mismatch", mismatch_off=(part,))
        obj, scene = plant._jobs(REQUESTS)[0].mismatch
        assert (obj, scene) != full and part in repr(plant)
        assert (obj.bumps == ()) == (part == "shape")
        assert (obj.inertia_scale == (1.0, 1.0, 1.0)) == (part == "mass")
        assert (scene.ripple == 0.0) == (part == "belts")
        physics = _scene_config(draw_scene(1), draw_object(1, "o3"), 0, scene).physics
        assert (physics.solver == "Newton") == (part == "contact")
    everything = ("shape", "mass", "belts", "contact")
    off = EmulatedPlant(1, kind="mismatch", mismatch_off=everything)
    assert off.weigh("o3") == EmulatedPlant(1).weigh("o3")
