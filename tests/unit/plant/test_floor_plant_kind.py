"""A floor on the mismatch plant: the plant's kind beside its seed in the floor's secret
file, and the modules' plant physics of that kind."""

from __future__ import annotations

import numpy as np
import pytest

from transfertwin import InputError
from transfertwin.cps.floor import read_plant_kind, read_plant_seed, write_plant_seed
from transfertwin.plant import PlantPhysics


def test_the_secret_file_names_a_kind_other_than_in_class(tmp_path) -> None:
    plain = write_plant_seed(tmp_path / "a.secret", 7)
    assert plain.read_text() == "7\n"  # the in-class plant's file is unchanged
    assert (read_plant_seed(plain), read_plant_kind(plain)) == (7, "in-class")
    other = write_plant_seed(tmp_path / "b.secret", 7, "mismatch")
    assert other.read_text() == "7 mismatch\n"
    assert (read_plant_seed(other), read_plant_kind(other)) == (7, "mismatch")
    bad = tmp_path / "c.secret"
    bad.write_text("7 mismatch extra\n")
    with pytest.raises(InputError, match="non-negative integer"):
        read_plant_kind(bad)


def test_the_mismatch_plants_physics_differ_from_the_in_class_plants() -> None:
    same = PlantPhysics(7).system("o1")
    other = PlantPhysics(7, "mismatch").system("o1")
    assert other is not same
    # its structural differences are in the compiled model: geometry, mass distribution
    differs = (other.model.nbody != same.model.nbody
               or other.model.ngeom != same.model.ngeom
               or not np.allclose(other.model.body_inertia, same.model.body_inertia))  # fmt: skip
    assert differs
    with pytest.raises(InputError, match="in-class, mismatch, bullet"):
        PlantPhysics(7, "havok")


def test_a_module_on_the_bullet_plant_picks_up_and_delivers_through_its_environment() -> None:
    """The floor module's environment steps the PyBullet plant as it steps MuJoCo's: the
    object put on the unit's loading point, a pick-up run by the study's controller on the
    scaled clock, docked on at another unit, the delivery; the same inputs give the same
    bits, and another plant seed other physics."""
    from transfertwin.cps.apps import Environment
    from transfertwin.ots import TransferDirection
    from transfertwin.plant._bullet import BulletTransferSystem
    from transfertwin.sim import DockingError, SceneConfig
    from transfertwin.study.experiment import scene_controller

    def operate(seed: int):
        env = Environment(SceneConfig(), 0.0, PlantPhysics(seed, "bullet").system)
        env.load_object_at_unit("o3", "TU_A", DockingError.from_mm_deg(-2.0, 1.0, 0.3))
        system = env.system
        assert isinstance(system, BulletTransferSystem)
        assert system.observe()[0] == 1.0  # on the unit's belts
        steps = []
        env.on_step(lambda sys_, unit: steps.append(unit))
        outcomes = []
        for unit, direction in (("TU_A", TransferDirection.TU_TO_TM),
                                ("TU_C", TransferDirection.TM_TO_TU)):  # fmt: skip
            if unit == "TU_C":
                env.dock(unit, DockingError.from_mm_deg(1.0, -1.5, -0.2))
            ctl = scene_controller(env.scene, system.tm, system.tu, system, env.clock)
            outcomes.append(ctl.transfer(direction, "front", None).y)
        return outcomes, system.object_qpos(), steps, env.clock.now()

    outcomes, qpos, steps, t = operate(7)
    assert outcomes == [1, 1], outcomes  # picked up from TU_A, delivered at TU_C
    assert steps and set(steps) <= {"TU_A", "TU_C"} and t > 0.5
    again, qpos_again, _, _ = operate(7)
    assert again == outcomes and np.array_equal(qpos, qpos_again)
    assert not np.array_equal(operate(8)[1], qpos)


def test_a_floor_on_the_bullet_plant_refuses_the_depth_camera_in_one_line() -> None:
    from transfertwin.plant import check_camera

    check_camera("bullet", "truth", "sampled")
    check_camera("mismatch", "camera", "navigated")
    with pytest.raises(InputError, match=r"operation\.sensor = camera"):
        check_camera("bullet", "camera", "sampled")
    with pytest.raises(InputError, match="--docking navigated"):
        check_camera("bullet", "truth", "navigated")


def test_the_secret_file_names_the_mismatch_parts_switched_off(tmp_path) -> None:
    """An ablation on a floor: the parts after the kind, read back in order."""
    from transfertwin.cps.floor import read_plant_off

    path = write_plant_seed(tmp_path / "d.secret", 7, "mismatch", ("sag", "contact"))
    assert path.read_text() == "7 mismatch off=contact,sag\n"
    assert (read_plant_seed(path), read_plant_kind(path), read_plant_off(path)) == (
        7, "mismatch", ("contact", "sag"))
    assert read_plant_off(write_plant_seed(tmp_path / "e.secret", 7, "mismatch")) == ()


def test_a_part_switched_off_is_the_in_class_plants_in_the_modules_physics() -> None:
    """Mass off: the core's inertia and centre of mass are the in-class plant's again,
    while the rest of the mismatch (its bodies and geometry) stays."""
    whole = PlantPhysics(7, "mismatch").system("o1").model
    no_mass = PlantPhysics(7, "mismatch", ("mass",)).system("o1").model
    in_class = PlantPhysics(7).system("o1").model
    assert (no_mass.nbody, no_mass.ngeom) == (whole.nbody, whole.ngeom)
    assert not np.allclose(no_mass.body_ipos, whole.body_ipos)
    core = 1 + int(np.argmax(in_class.body_mass[1:]))
    assert np.allclose(no_mass.body_ipos[core], in_class.body_ipos[core])
    with pytest.raises(InputError, match="mismatch parts"):
        PlantPhysics(7, "in-class", ("mass",))
    with pytest.raises(InputError, match="mismatch parts"):
        PlantPhysics(7, "mismatch", ("colour",))


def test_cps_up_refuses_unknown_parts_in_one_line() -> None:
    from transfertwin.cli._cps_floor import _mismatch_off

    assert _mismatch_off(" shape, sag ", "mismatch") == ("shape", "sag")
    assert _mismatch_off("", "in-class") == ()
    with pytest.raises(InputError, match="--plant-mismatch-off"):
        _mismatch_off("colour", "mismatch")
    with pytest.raises(InputError, match="--plant-mismatch-off"):
        _mismatch_off("shape", "in-class")
