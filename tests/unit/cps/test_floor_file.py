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
