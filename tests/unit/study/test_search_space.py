"""The search space of `calibrate tune`: parsing, checks and how a trial's values apply."""

from __future__ import annotations

import pytest

from transfertwin import InputError
from transfertwin.sim import SceneConfig
from transfertwin.study.calibration import parse_space, scene_with, trial_proxies

FULL = (
    "physics.solref[0]=0.002:0.02:log,mu=0.3:0.8,gap_mm=8:16,"
    "layout.pulley_radius_m=0.010:0.025,physics.iterations=10:60,object.o1.front_depth_mm=0:30"
)


def test_space_parses_sorted_and_round_trips():
    space = parse_space(FULL, SceneConfig())
    assert space.names() == sorted(space.names())
    by_name = {d.name: d for d in space.dims}
    assert by_name["physics.solref[0]"].log and not by_name["mu"].log
    assert by_name["physics.iterations"].integer and not by_name["gap_mm"].integer
    assert by_name["object.o1.front_depth_mm"].object_face == ("o1", "front")
    assert parse_space(space.text(), SceneConfig()) == space
    assert space.object_ids() == ["o1"]


def test_trial_values_apply_to_the_scene_and_the_proxies(tmp_path):
    params = {"mu": 0.5, "gap_mm": 9.0, "physics.solref[0]": 0.01,
              "layout.pulley_radius_m": 0.015, "object.o1.back_depth_mm": 20.0,
              "object.o1.front_depth_mm": 5.0}  # fmt: skip
    scene = scene_with(SceneConfig(), params)
    assert (scene.mu, scene.gap_m, scene.physics.solref) == (0.5, 0.009, (0.01, 1.0))
    assert scene.layout.pulley_radius_m == 0.015
    proxies = trial_proxies(params, {"o1": "o1", "o18": "o18"})
    assert list(proxies) == ["o1"]
    spec = proxies["o1"]
    assert spec.base == "o1"
    assert [(p.face, p.depth_m) for p in spec.protrusions] == [("front", 0.005), ("back", 0.02)]
    mesh = tmp_path / "m.stl"
    mesh.write_bytes(b"")
    assert trial_proxies(params, {"o1": str(mesh)})["o1"].base == str(mesh.resolve())


def test_depth_penalty_weights_each_face_by_its_share_of_rows():
    space = parse_space("object.o1.front_depth_mm=0:20,object.o1.back_depth_mm=0:40",
                        SceneConfig())  # fmt: skip
    rows = [{"object_id": "o1", "face": "front"}] * 3 + [{"object_id": "o1", "face": "back"}]
    params = {"object.o1.front_depth_mm": 20.0, "object.o1.back_depth_mm": 10.0}
    assert space.depth_penalty(params, rows) == pytest.approx(0.75 * 1.0 + 0.25 * 0.25)
    zero = dict.fromkeys(params, 0.0)
    assert space.depth_penalty(zero, rows) == 0.0


def test_a_shift_dimension_moves_the_proxys_centre_of_mass_and_is_penalised():
    space = parse_space("object.o18.com_shift_mm=-20:10,mu=0.3:0.8", SceneConfig())
    dim = next(d for d in space.dims if d.name == "object.o18.com_shift_mm")
    assert dim.shifted_object == "o18" and dim.object_face is None
    assert space.object_ids() == ["o18"] and space.object_dims() == []
    params = {"mu": 0.5, "object.o18.com_shift_mm": -10.0}
    assert scene_with(SceneConfig(), params).mu == 0.5  # the shift is no scene setting
    spec = trial_proxies(params, {"o18": "o18"})["o18"]
    assert spec.com_shift_m == pytest.approx(-0.010)
    # o18 keeps its shipped feature (back 26 mm) when only its mass is tuned
    assert [(p.face, p.depth_m) for p in spec.protrusions] == [("front", 0.0), ("back", 0.026)]
    rows = [{"object_id": "o18", "face": "front"}] * 3 + [{"object_id": "o1", "face": "back"}]
    assert space.depth_penalty(params, rows) == pytest.approx(0.75 * 10.0 / 20.0)
    assert space.depth_penalty({**params, "object.o18.com_shift_mm": 0.0}, rows) == 0.0


@pytest.mark.parametrize(
    ("text", "needle"),
    [
        ("friction=0:1", "unknown setting"),
        ("physics.bogus=0:1", "unknown setting"),
        ("mu=0.8:0.3", "LO must be below HI"),
        ("mu=0.5:0.5", "LO must be below HI"),
        ("mu=0:1:log", "LO > 0"),
        ("mu=0.1:0.5:lin", "NAME=LO:HI"),
        ("mu", "NAME=LO:HI"),
        ("mu=a:1", "not a number"),
        ("mu=0:inf", "finite"),
        ("physics.solver=0:1", "not a numeric"),
        ("physics.multiccd=0:1", "not a numeric"),
        ("physics.solref=0.001:0.01", "tuple"),
        ("physics.solref[2]=0.001:0.01", "index 0..1"),
        ("physics.condim=3:6", "condim=5"),
        ("physics.iterations=1.5:6", "integer"),
        ("layout.pulley_radius_m=0.01:0.4", "too large"),
        ("gap_mm=5:600", "gap"),
        ("gap_mm=5:10,gap_m=0.01:0.02", "twice"),
        ("object.o1.side_depth_mm=0:10", "front_depth_mm"),
        ("object.o1.front_depth_mm=0:200", "0..100"),
        ("object.o1.com_shift_mm=-60:10", "-50..50"),
        ("object.o1.com_shift_mm=1:10:log", "no log"),
        ("object.o1.mass_mm=0:1", "com_shift_mm"),
        ("", "empty"),
    ],
)
def test_bad_spaces_are_input_errors(text, needle):
    with pytest.raises(InputError, match=needle):
        parse_space(text, SceneConfig())
