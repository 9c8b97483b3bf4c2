"""The transfer system in PyBullet (issue 29, item 3): the same plant as the MuJoCo scene's,
belts that carry, a transfer that runs unchanged through `run_experiment`, and the same bits
for the same inputs."""

from __future__ import annotations

import dataclasses
import math
import pickle

import numpy as np
import pytest

from transfertwin._errors import InputError
from transfertwin.plant import PLANT_COLUMNS, EmulatedPlant, PlantRequest
from transfertwin.plant._bullet import BulletTransferSystem
from transfertwin.plant._plant import _fresh_bullet_system, _scene_config, _system
from transfertwin.plant._truth import draw_object, draw_scene
from transfertwin.sim import DockingError, SceneConfig
from transfertwin.study.experiment import ExperimentSpec, run_experiment

BOX = np.array([[x, y, z] for x in (-0.05, 0.05) for y in (-0.04, 0.04) for z in (-0.02, 0.02)])


def _plant_system(seed: int, object_id: str) -> tuple[BulletTransferSystem, SceneConfig]:
    """The in-class plant's hidden object and scene of `seed`, in Bullet (a new system)."""
    obj, scene = draw_object(seed, object_id), draw_scene(seed)
    return _fresh_bullet_system(obj, scene), _scene_config(scene, obj)


def test_a_running_belt_carries_an_object_at_belt_speed_and_cuts_the_barriers() -> None:
    cfg = SceneConfig()
    system = BulletTransferSystem((BOX,), 1.0, np.zeros(3), np.diag([1e-3] * 3), cfg)
    system.reset(DockingError())
    system.place("front", 0.0, -0.45, 0.0)
    system.clock.wait(0.3)
    rest = system.observe()
    assert system.object_rest_speed() < 1e-3  # at rest on the stopped belts
    assert rest[3] == pytest.approx(0.02, abs=1e-3) and rest[4] == pytest.approx(0.05, abs=1e-4)
    for belt in ("left", "right"):
        system.tm.set_belt_speed(belt, 0.15)
    system.clock.wait(0.5)  # accelerate
    x0, t0 = system.observe()[1], system.clock.now()
    system.clock.wait(1.0)
    speed = (system.observe()[1] - x0) / (system.clock.now() - t0)
    assert speed == pytest.approx(0.15, rel=0.02)
    assert system.tm.belt_speed("left") == 0.15
    # the TM's far barrier (15 mm from its far end) sees a box placed over it
    system.reset(DockingError())
    system.place("front", 0.0, -cfg.layout.tm_length_m + 0.015, 0.0)
    system.clock.wait(0.05)
    assert system.tm.barriers() == {"near": False, "far": True}
    assert system.tu.barriers() == {"near": False, "far": False}


def test_the_bullet_plant_builds_the_same_scene_as_the_mujoco_one() -> None:
    """Same object pose in, nearly the same settled state out: the geometry, frames and
    mass properties agree (the engines differ only in contact detail)."""
    bullet, cfg = _plant_system(1, "o7")
    spec = ExperimentSpec("o7", "front", "left", 0, scene=cfg, seed=3)
    a = run_experiment(spec, system=bullet).state_pre
    b = run_experiment(spec, system=_system(draw_object(1, "o7"), draw_scene(1))).state_pre
    assert np.allclose(a[1:3], b[1:3], atol=0.002)  # x, y of the AABB centre
    assert np.allclose(a[4:7], b[4:7], atol=0.002)  # AABB half sizes
    assert abs(a[3] - b[3]) < 0.003  # z: Bullet's margin against MuJoCo's soft contact
    assert abs(math.remainder(a[7] - b[7], 2 * math.pi)) < 0.01


def test_a_transfer_runs_unchanged_and_gives_the_same_bits_for_the_same_inputs() -> None:
    system, cfg = _plant_system(1, "o7")
    spec = ExperimentSpec("o7", "front", "left", 0, docking_error=DockingError(), scene=cfg,
                          seed=3)  # fmt: skip
    first = run_experiment(spec, system=system)
    assert first.status == "ok" and first.success == 1 and first.y2 == 1
    # another experiment in the same system, then the first again: nothing carries over
    other = dataclasses.replace(spec, face="back", theta_deg=180, seed=4)
    run_experiment(other, system=system)
    again = run_experiment(spec, system=system)
    fresh = run_experiment(spec, system=_plant_system(1, "o7")[0])
    for result in (again, fresh):
        assert result == first and result.t_end_s == first.t_end_s
        assert result.state_end_2 == first.state_end_2


REQUESTS = [PlantRequest("o7", "front", "left", 0), PlantRequest("o3", "back", "both", 90)]


def test_the_bullet_plant_is_the_in_class_plant_in_another_engine() -> None:
    plant, in_class = EmulatedPlant(2, kind="bullet"), EmulatedPlant(2)
    jobs, same = plant._jobs(REQUESTS), in_class._jobs(REQUESTS)
    assert [j.engine for j in jobs] == ["bullet", "bullet"]
    assert [j.engine for j in same] == ["mujoco", "mujoco"]
    # the same hidden object, scene, station, docking error, placement seeds and flip
    assert [dataclasses.replace(j, engine="mujoco") for j in jobs] == same
    with pytest.raises(InputError, match="--plant-kind"):
        EmulatedPlant(2, kind="Bullet")
    with pytest.raises(InputError, match="mismatch plant"):
        EmulatedPlant(2, kind="bullet", mismatch_off=("sag",))


def test_the_bullet_plant_hides_its_values_like_the_in_class_one() -> None:
    plant = EmulatedPlant(3, kind="bullet")
    public = {n for n in dir(plant) if not n.startswith("_")}
    assert public == {n for n in dir(EmulatedPlant(3)) if not n.startswith("_")}
    assert not hasattr(plant, "__dict__")
    assert repr(plant) == "EmulatedPlant(seed=3, kind='bullet')" and plant.kind == "bullet"
    with pytest.raises(TypeError):
        pickle.dumps(plant)
    fp = plant.fingerprint(["o3"])
    assert len(fp) == 64 and fp != EmulatedPlant(3).fingerprint(["o3"])
    assert fp == EmulatedPlant(3, kind="bullet").fingerprint(["o3"])
    scene, obj = draw_scene(3), draw_object(3, "o3")
    hidden = [scene.mu, scene.gap_m, scene.belt_speed_scale, obj.mass_scale, *obj.com_offset_m]
    shown = fp + repr(plant) + str(plant.weigh("o3"))
    assert not any(str(v) in shown or f"{v:.4g}" in fp for v in hidden)
    assert plant.weigh("o3") == EmulatedPlant(3).weigh("o3")  # the same objects


def test_a_bullet_plant_runs_valid_reproducible_rows_and_operates() -> None:
    rows = EmulatedPlant(1, kind="bullet").run(REQUESTS)
    assert rows == EmulatedPlant(1, kind="bullet").run(REQUESTS)
    assert [tuple(r) for r in rows] == [PLANT_COLUMNS] * 2
    assert all(r["success"] in (0, 1) for r in rows)
    assert [r["experiment_id"] for r in rows] == [0, 1]
    in_class = EmulatedPlant(1).run(REQUESTS)
    drawn = [c for c in PLANT_COLUMNS if c != "success"]
    assert [[r[c] for c in drawn] for r in rows] == [[r[c] for c in drawn] for r in in_class]
    plant = EmulatedPlant(1, kind="bullet")
    ops = plant.operate(REQUESTS[:1])
    assert set(ops[0]) == {*PLANT_COLUMNS, "transfer_time_s"}
    assert ops[0]["transfer_time_s"] > 0 and ops[0]["success"] == rows[0]["success"]
    with pytest.raises(InputError, match="cannot be observed"):
        plant.observe(ops[0])


@pytest.mark.slow
def test_a_bullet_plant_gives_the_same_rows_with_any_number_of_workers() -> None:
    requests = [*REQUESTS, PlantRequest("o12", "back", "right", 180)]
    one = EmulatedPlant(1, kind="bullet").run(requests)
    assert EmulatedPlant(1, kind="bullet").run(requests, workers=2) == one


def test_a_rehearsal_takes_the_bullet_plant() -> None:
    from transfertwin.rehearsal import RehearsalConfig

    cfg = RehearsalConfig(plant_seed=1, objects=("o3",), calibration_experiments=20,
                          plant_kind="bullet")  # fmt: skip
    assert cfg.plant_kind == "bullet"
    with pytest.raises(InputError, match="--mismatch-off"):
        RehearsalConfig(plant_seed=1, objects=("o3",), calibration_experiments=20,
                        plant_kind="bullet", mismatch_off=("sag",))  # fmt: skip
