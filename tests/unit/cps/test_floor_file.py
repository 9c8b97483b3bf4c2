"""Floor files and asset configuration files (docs/architecture.md, "Deployment")."""

from __future__ import annotations

from pathlib import Path

import pytest

from transfertwin._errors import InputError
from transfertwin.cps import (
    AssetConfig,
    default_floor_spec,
    demo_descriptors,
    floor_toml,
    load_asset_config,
    load_floor,
    write_asset_config,
)

EXAMPLES = Path(__file__).resolve().parents[3] / "examples"


def test_the_default_floor_is_the_demo_cps_and_round_trips(tmp_path):
    spec = default_floor_spec()
    assert spec.descriptors() == demo_descriptors()
    (tmp_path / "f.toml").write_text(floor_toml(spec))
    assert load_floor(tmp_path / "f.toml") == spec
    assert load_floor(EXAMPLES / "floor-demo.toml") == spec


def test_the_large_example_has_3_modules_8_units_20_objects_on_a_drivable_floor():
    from transfertwin.cps.apps import FloorRobot

    spec = load_floor(EXAMPLES / "floor-large.toml")
    assert (len(spec.modules), len(spec.units), len(spec.objects)) == (3, 8, 20)
    floor = spec.shop_floor()
    for m in spec.modules:  # every start pose is free
        FloorRobot(floor, home=m.home)


@pytest.mark.parametrize(("edit", "message"), [
    (lambda t: t.replace('at = "TU_A"', 'at = "TU_X"', 1), "which is no transfer unit"),
    (lambda t: t.replace('id = "o5"', 'id = "o1"'), "appears twice"),
    (lambda t: t.replace('mount = "left"', 'mount = "up"', 1), "mount must be left or right"),
    (lambda t: t.replace('"KG"]', '"Hub"]'), "unknown logical asset"),
    (lambda t: t.replace(', "KG"]', "]"), "needs the logical asset KG"),
    (lambda t: t.replace('id = "o5"', 'id = "o99"'), "not a built-in core"),
    (lambda t: t.replace("x_m = 2.6", 'x_m = "far"'), "x_m must be a finite number"),
    (lambda t: "size = 3\n" + t, "unknown key .size."),
    (lambda t: t + "\n[[", "not a readable TOML floor file"),
])  # fmt: skip
def test_a_bad_floor_file_is_one_clear_error(tmp_path, edit, message):
    path = tmp_path / "bad.toml"
    path.write_text(edit(floor_toml(default_floor_spec())))
    with pytest.raises(InputError, match=message):
        load_floor(path)


def _config(tmp_path: Path, **kw) -> AssetConfig:
    base = dict(asset_id="TU_A", floor_file=tmp_path / "floor.toml", host="127.0.0.7",
                port=48401, seeds=("opc.tcp://127.0.0.2:48400/transfertwin/KG",),
                cert_dir=tmp_path / "c", trust_dir=tmp_path / "t",
                credentials_file=tmp_path / "credentials.json",
                state_dir=tmp_path / "s")  # fmt: skip
    return AssetConfig(**{**base, **kw})


def test_an_asset_config_round_trips_through_its_file(tmp_path):
    cfg = _config(tmp_path, lease_s=2.5, seed=3, docking="navigated")
    path = write_asset_config(tmp_path / "assets" / "TU_A.toml", cfg)
    assert load_asset_config(path) == cfg
    assert cfg.endpoint == "opc.tcp://127.0.0.7:48401/transfertwin/TU_A"


@pytest.mark.parametrize(("kw", "message"), [
    ({"host": "192.0.2.10"}, "beyond loopback\\) needs allow_remote"),
    ({"host": "192.0.2.10", "allow_remote": True, "insecure": True}, "insecure .* loopback only"),
    ({"credentials_file": None}, "needs \\[security\\] credentials"),
    ({"host": "localhost"}, "host must be an IP address"),
    ({"lease_s": 0.1}, "lease_s must be at least 0.5"),
    ({"port": 0}, "port must be 1..65535"),
])  # fmt: skip
def test_an_asset_binds_beyond_loopback_only_when_told_and_never_insecure(tmp_path, kw, message):
    with pytest.raises(InputError, match=message):
        _config(tmp_path, **kw)


def test_a_secure_remote_asset_is_allowed_with_the_flag(tmp_path):
    cfg = _config(tmp_path, host="192.0.2.10", allow_remote=True)
    assert cfg.host == "192.0.2.10" and not cfg.insecure


def test_a_missing_key_in_an_asset_file_is_named(tmp_path):
    path = tmp_path / "a.toml"
    path.write_text('[asset]\nid = "TU_A"\n[network]\nhost = "127.0.0.2"\nport = 1\n')
    with pytest.raises(InputError, match="missing 'floor'"):
        load_asset_config(path)


def test_hal_kinds_round_trip_through_the_floor_and_asset_files(tmp_path):
    from transfertwin.cps import HalConfig

    text = floor_toml(default_floor_spec()).replace(
        'mount = "right"', 'mount = "right"\nhal = "remote"\n'
        'gateway = "opc.tcp://127.0.0.1:4840"', 1)  # fmt: skip
    (tmp_path / "f.toml").write_text(text)
    spec = load_floor(tmp_path / "f.toml")
    assert spec.hal_of("TU_B") == ("remote", "opc.tcp://127.0.0.1:4840")
    assert spec.hal_of("TU_A") == ("virtual", None) and not spec.uses_plant()
    plant = spec.with_hal("plant")  # what cps up --plant-seed does; a remote unit keeps its HAL
    assert plant.uses_plant() and plant.hal_of("TM_1") == ("plant", None)
    assert plant.hal_of("TU_B")[0] == "remote" and plant.hal_of("TU_A")[0] == "plant"
    (tmp_path / "p.toml").write_text(floor_toml(plant))
    assert load_floor(tmp_path / "p.toml") == plant
    (tmp_path / "g.toml").write_text('hal = "plant"\n' + floor_toml(default_floor_spec()))
    assert load_floor(tmp_path / "g.toml").hal_of("TU_C") == ("plant", None)
    hal = HalConfig("remote", endpoint="opc.tcp://127.0.0.1:4840", insecure=True, poll_s=0.02,
                    nodes=(("barrier_far", "ns=3;i=7"),))  # fmt: skip
    cfg = _config(tmp_path, hal=hal)
    path = write_asset_config(tmp_path / "assets" / "TU_B.toml", cfg)
    assert load_asset_config(path) == cfg
    assert hal.node_ids("TU_B") == {"belt_left": "ns=2;s=TU_B.BeltSpeedLeft",
                                    "belt_right": "ns=2;s=TU_B.BeltSpeedRight",
                                    "barrier_near": "ns=2;s=TU_B.BarrierNear",
                                    "barrier_far": "ns=3;i=7",
                                    "pose_x": "ns=2;s=TU_B.PoseX",
                                    "pose_y": "ns=2;s=TU_B.PoseY",
                                    "pose_theta": "ns=2;s=TU_B.PoseTheta",
                                    "command": "ns=2;s=TU_B.Command",
                                    "command_state": "ns=2;s=TU_B.CommandState",
                                    "object_state": "ns=2;s=TU_B.ObjectState"}  # fmt: skip
    # a remote module: its gateway in the floor file, a gateway trust folder of its own
    text = floor_toml(default_floor_spec()).replace(
        'standby = false', 'standby = false\nhal = "remote"\n'
        'gateway = "opc.tcp://127.0.0.1:4841"', 1)  # fmt: skip
    (tmp_path / "m.toml").write_text(text)
    spec = load_floor(tmp_path / "m.toml")
    assert spec.hal_of("TM_1") == ("remote", "opc.tcp://127.0.0.1:4841")
    assert spec.with_hal("plant").hal_of("TM_1") == ("remote", "opc.tcp://127.0.0.1:4841")
    (tmp_path / "m2.toml").write_text(floor_toml(spec))
    assert load_floor(tmp_path / "m2.toml") == spec
    hal = HalConfig("remote", endpoint="opc.tcp://127.0.0.1:4841", trust_dir=tmp_path / "gw",
                    nodes=(("object_state", "ns=4;s=Vision.Box"),))  # fmt: skip
    cfg = _config(tmp_path, hal=hal)
    path = write_asset_config(tmp_path / "assets" / "TM_1.toml", cfg)
    assert load_asset_config(path) == cfg
    assert hal.node_ids("TM_1")["object_state"] == "ns=4;s=Vision.Box"
    seeded = _config(tmp_path, hal=HalConfig("plant", plant_seed_file=tmp_path / "plant.secret"))
    path = write_asset_config(tmp_path / "assets" / "TM_1.toml", seeded)
    assert load_asset_config(path) == seeded


@pytest.mark.parametrize(("edit", "message"), [
    (lambda t: t.replace('mount = "right"', 'mount = "right"\nhal = "remote"', 1),
     "remote HAL needs gateway"),
    (lambda t: t.replace('standby = false', 'standby = false\nhal = "remote"', 1),
     "module TM_1: a remote HAL needs gateway"),
    (lambda t: t.replace('standby = false', 'standby = false\ngateway = "opc.tcp://h:1"', 1),
     "module TM_1: a remote HAL needs gateway"),
    (lambda t: t.replace('standby = false', 'standby = false\nhal = "real"', 1),
     "module TM_1: hal must be virtual, plant or remote"),
    (lambda t: 'hal = "remote"\n' + t, "hal must be virtual or plant"),
    (lambda t: t.replace('mount = "right"', 'mount = "right"\nhal = "real"', 1),
     "hal must be virtual, plant or remote"),
])  # fmt: skip
def test_a_bad_hal_in_a_floor_file_is_one_clear_error(tmp_path, edit, message):
    path = tmp_path / "bad.toml"
    path.write_text(edit(floor_toml(default_floor_spec())))
    with pytest.raises(InputError, match=message):
        load_floor(path)


@pytest.mark.parametrize(("hal", "message"), [
    ({"kind": "real"}, "kind must be one of virtual, plant, remote"),
    ({"kind": "plant"}, "needs plant_seed_file"),
    ({"kind": "remote"}, "needs endpoint"),
    ({"kind": "remote", "endpoint": "opc.tcp://192.0.2.4:4840", "insecure": True},
     "insecure .* loopback only"),
    ({"kind": "remote", "endpoint": "opc.tcp://127.0.0.1:4840", "poll_s": 0.0},
     "poll_s must be"),
])  # fmt: skip
def test_a_bad_hal_in_an_asset_config_is_one_clear_error(tmp_path, hal, message):
    from transfertwin.cps import HalConfig

    with pytest.raises(InputError, match=message):
        _config(tmp_path, hal=HalConfig(**hal))


def test_an_unknown_hal_key_in_an_asset_file_is_named(tmp_path):
    path = write_asset_config(tmp_path / "a.toml", _config(tmp_path))
    path.write_text(path.read_text() + 'gatway = "opc.tcp://127.0.0.1:1"\n')
    with pytest.raises(InputError, match="\\[hal\\] unknown key 'gatway'"):
        load_asset_config(path)


def test_a_plant_floor_needs_its_seed_and_keeps_it_out_of_the_asset_files(tmp_path):
    import stat

    from transfertwin.cps import prepare_floor

    plant = default_floor_spec().with_hal("plant")
    with pytest.raises(InputError, match="--plant-seed"):
        prepare_floor(plant, tmp_path / "w", insecure=True)
    configs = prepare_floor(plant, tmp_path / "w", insecure=True, plant_seed=918273)
    secret = tmp_path / "w" / "plant.secret"
    assert secret.read_text().strip() == "918273"
    assert stat.S_IMODE(secret.stat().st_mode) == 0o600
    assert configs["TM_1"].hal.kind == "plant" and configs["TU_A"].hal.kind == "plant"
    assert configs["o1"].hal.kind == "virtual" and configs["KG"].hal.plant_seed_file is None
    for f in (tmp_path / "w").rglob("*.toml"):
        assert "918273" not in f.read_text(), f


_BOUND = """
name = "bound"
logical = ["KG", "TMS"]

[[module]]
id = "TM_1"
x_m = 6.0
y_m = 5.2

[bind]
"""


@pytest.mark.parametrize(("bind", "message"), [
    ('TU_X = "198.18.0.2"', "no such asset"),
    ('KG = "kg.local"', "not an IPv4 address"),
    ('KG = "198.18.0.2:0"', "port must be 1..65535"),
    ('KG = "198.18.0.2:4840"\nTMS = "198.18.0.2:4840"', "another asset's too"),
    ("KG = 4840", r"must map an asset id to \"ADDRESS\[:PORT\]\""),
])  # fmt: skip
def test_a_bad_bind_table_is_one_clear_error(tmp_path, bind, message):
    path = tmp_path / "bound.toml"
    path.write_text(_BOUND + bind + "\n")
    with pytest.raises(InputError, match=message):
        load_floor(path)


def test_bound_assets_listen_where_the_floor_says_with_security_only(tmp_path):
    from transfertwin.cps import prepare_floor

    path = tmp_path / "bound.toml"
    path.write_text(_BOUND + 'KG = "198.18.0.2"\nTMS = "198.18.0.2"\nTM_1 = "198.18.0.3:4900"\n')
    floor = load_floor(path)
    assert load_floor(_written(tmp_path, floor)) == floor  # [bind] round-trips
    with pytest.raises(InputError, match="only with security"):
        prepare_floor(floor, tmp_path / "insecure", insecure=True)
    cfgs = prepare_floor(floor, tmp_path / "w")
    where = {a: (c.host, c.port, c.allow_remote) for a, c in cfgs.items()}
    assert where == {"KG": ("198.18.0.2", 4840, True), "TMS": ("198.18.0.2", 4841, True),
                     "TM_1": ("198.18.0.3", 4900, True)}  # fmt: skip
    assert cfgs["TM_1"].seeds == ("opc.tcp://198.18.0.2:4840/transfertwin/KG",
                                  "opc.tcp://198.18.0.2:4841/transfertwin/TMS")  # fmt: skip


def _written(tmp_path: Path, floor) -> Path:
    out = tmp_path / "again.toml"
    out.write_text(floor_toml(floor))
    return out


def test_each_asset_runs_from_its_bundle_alone_anywhere(tmp_path):
    """`cps up` writes a folder per asset with every path relative to it: copied elsewhere
    (the work folder gone), it names nothing outside itself; the study store is in the
    Experiment Manager's bundle only, and no asset's floor copy names it."""
    import shutil
    from dataclasses import replace

    from transfertwin.cps import bundle_config, load_asset_config, prepare_floor

    store = tmp_path / "quick.sqlite"
    store.write_bytes(b"a study store")
    floor = default_floor_spec()
    floor = replace(floor, operation=replace(floor.operation, study=str(store)))
    prepare_floor(floor, tmp_path / "w", insecure=True)
    for aid in ("EM", "TMS", "TU_A"):
        shutil.copytree(tmp_path / "w" / "assets" / aid, tmp_path / "host" / aid)
    shutil.rmtree(tmp_path / "w")
    for aid in ("EM", "TMS", "TU_A"):
        bundle = tmp_path / "host" / aid
        cfg = load_asset_config(bundle_config(bundle))
        paths = [cfg.floor_file, cfg.cert_dir, cfg.trust_dir, cfg.state_dir]
        assert all(p.is_relative_to(bundle) for p in paths), (aid, paths)
        assert load_floor(cfg.floor_file).operation.study is None
        assert (cfg.study_file is not None) == (aid == "EM")
    em = load_asset_config(bundle_config(tmp_path / "host" / "EM"))
    assert em.study_file == tmp_path / "host" / "EM" / "study.sqlite"
    assert em.study_file.read_bytes() == b"a study store"
