"""An asset's HAL (cps.hal._local): a plant floor's module simulates its docked pair with the
plant's hidden physics, its controller keeps the twin's scene; the seed file."""

from __future__ import annotations

import pytest

from transfertwin._errors import InputError
from transfertwin.cps import AssetConfig, HalConfig
from transfertwin.cps.floor import read_plant_seed, write_plant_seed
from transfertwin.cps.hal import environment_for


def _cfg(tmp_path, hal: HalConfig) -> AssetConfig:
    return AssetConfig(asset_id="TM_1", floor_file=tmp_path / "floor.toml", host="127.0.0.1",
                       port=48400, seeds=(), cert_dir=tmp_path / "c", trust_dir=tmp_path / "t",
                       credentials_file=None, state_dir=tmp_path / "s", insecure=True,
                       hal=hal)  # fmt: skip


def test_a_plant_module_steps_the_plants_hidden_system_with_the_twins_controller_scene(tmp_path):
    from transfertwin.cps.hal import load_scene
    from transfertwin.plant import PlantPhysics
    from transfertwin.study.experiment import system_for

    seed_file = write_plant_seed(tmp_path / "plant.secret", 918273)
    assert read_plant_seed(seed_file) == 918273
    scene = load_scene()
    virtual = environment_for(_cfg(tmp_path, HalConfig()), scene)
    plant = environment_for(_cfg(tmp_path, HalConfig("plant", plant_seed_file=seed_file)), scene)
    assert plant.scene is scene is virtual.scene  # the controller knows the twin's scene only
    twin = virtual.use("o1")
    hidden = plant.use("o1")
    assert twin is system_for("o1", "m", scene) and hidden is not twin
    assert plant.system is hidden and plant.object_ref == "o1"
    assert hidden is PlantPhysics(918273).system("o1")  # the same plant, the same system
    assert hidden is not PlantPhysics(918274).system("o1")
    # the plant's physics differ from the twin's (friction, gap: drawn, not the defaults)
    assert (hidden.cfg.mu, hidden.cfg.gap_m) != (twin.cfg.mu, twin.cfg.gap_m)
    assert plant.after_step in hidden.step_listeners  # the barriers follow its steps
    assert "918273" not in repr(PlantPhysics(918273))
    with pytest.raises(TypeError):
        __import__("pickle").dumps(PlantPhysics(918273))


def test_the_seed_file_and_hal_kinds_refuse_what_cannot_work(tmp_path):
    bad = tmp_path / "bad.secret"
    bad.write_text("-3\n")
    with pytest.raises(InputError, match="non-negative integer"):
        read_plant_seed(bad)
    with pytest.raises(InputError, match="cannot read the plant seed file"):
        read_plant_seed(tmp_path / "missing.secret")


def test_a_remote_module_simulates_nothing_its_world_is_at_the_gateway(tmp_path):
    from transfertwin.cps.hal import GatewayWorld, WallClock, load_scene

    remote = HalConfig("remote", endpoint="opc.tcp://127.0.0.1:4840", insecure=True)
    scene = load_scene()
    world = environment_for(_cfg(tmp_path, remote), scene)
    assert isinstance(world, GatewayWorld) and world.scene is scene
    assert world.object_ref is None  # no simulated system to load an object into
    world.docked_unit = "TU_A"
    world.undock()
    assert world.docked_unit is None
    # the wall clock: t0 is the first wait (the belts start), waits keep a fixed grid
    clock = WallClock()
    clock.start()
    assert clock.now() == 0.0
    for _ in range(3):
        clock.wait(0.02)
    assert 0.06 <= clock.now() < 0.2
