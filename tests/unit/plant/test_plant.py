"""The emulated plant: a seed reproduces the plant, and its hidden parameters stay hidden."""

from __future__ import annotations

import ast
import inspect
import pickle

import pytest

from transfertwin._errors import InputError
from transfertwin._layers import LAYERS
from transfertwin.objects._builtin import cores_data_dir
from transfertwin.objects._features import read_features
from transfertwin.plant import PLANT_COLUMNS, EmulatedPlant, PlantRequest
from transfertwin.plant._truth import FEATURE_DEPTH_M, P_PLAIN_FACE, draw_object, draw_scene

REQUEST = [PlantRequest("o3", "back", "both", 90)]


def test_same_seed_same_plant_and_rows_other_seed_other_plant() -> None:
    a, b, c = EmulatedPlant(5), EmulatedPlant(5), EmulatedPlant(6)
    assert a.fingerprint(["o3", "o7"]) == b.fingerprint(["o3", "o7"])
    assert a.fingerprint(["o3"]) != c.fingerprint(["o3"])
    rows_a, rows_b = a.run(REQUEST), b.run(REQUEST)
    assert rows_a == rows_b
    assert tuple(rows_a[0]) == PLANT_COLUMNS
    assert rows_a[0]["experiment_id"] == 0 and a.experiments_run == 1
    # the next experiment (id 1): same draws for the same seed, others for another seed
    ja, jb = a._jobs(REQUEST)[0], b._jobs(REQUEST)[0]
    jc = c._jobs(REQUEST + REQUEST)[1]
    assert ja.experiment_id == jb.experiment_id == jc.experiment_id == 1
    assert ja == jb
    assert ja.error_mm_deg != jc.error_mm_deg and ja.seeds != jc.seeds


def test_hidden_draws_depend_on_the_seed_and_differ_from_the_twin() -> None:
    assert draw_scene(1) == draw_scene(1) and draw_scene(1) != draw_scene(2)
    assert draw_object(1, "o3") == draw_object(1, "o3") != draw_object(2, "o3")
    shipped = read_features(cores_data_dir())["o3"]
    for seed in range(5):
        plant = draw_object(seed, "o3")
        assert set(plant.protrusions) != set(shipped)
        assert plant.com_offset_m != (0.0, 0.0, 0.0) and plant.mass_scale != 1.0


def test_feature_depths_follow_the_prior() -> None:
    from scipy.stats import binomtest

    faces = [p for seed in range(6) for i in range(1, 38)
             for p in draw_object(seed, f"o{i}").protrusions]  # fmt: skip
    plain = sum(p.depth_m == 0.0 for p in faces)
    assert binomtest(plain, len(faces), P_PLAIN_FACE).pvalue > 0.01
    depths = [p.depth_m for p in faces if p.depth_m]
    low, high = FEATURE_DEPTH_M
    assert all(low <= d <= high for d in depths)
    assert min(depths) < low + 0.002 and max(depths) > high - 0.002  # the whole range


def test_the_plant_exposes_no_hidden_parameter() -> None:
    plant = EmulatedPlant(3)
    public = {n for n in dir(plant) if not n.startswith("_")}
    assert public == {"seed", "kind", "stations", "experiments_run", "fingerprint", "run",
                      "operate", "weigh", "observe"}  # fmt: skip
    assert not hasattr(plant, "__dict__")  # slots only: no stray attributes
    assert repr(plant) == "EmulatedPlant(seed=3)"
    with pytest.raises(TypeError):
        pickle.dumps(plant)
    fp = plant.fingerprint(["o3"])
    assert len(fp) == 64 and str(draw_scene(3).mu) not in fp


def test_bad_requests_are_refused() -> None:
    with pytest.raises(InputError, match=r"Eq\. 6\.7"):
        PlantRequest("o3", "front", "left", 90)  # a single belt only near 0/180 degrees
    with pytest.raises(InputError, match="no object"):
        EmulatedPlant(0).run([PlantRequest("o99", "front", "both", 90)])
    with pytest.raises(InputError):
        EmulatedPlant(-1)


def test_no_twin_layer_can_import_the_plant() -> None:
    """Calibration, study and validation code lie below the plant: importing it upward is a
    layering violation that tests/unit/test_layering.py rejects."""
    twin = [name for name in LAYERS if name.startswith("study")] + ["sim", "objects"]
    assert all(LAYERS.index(name) < LAYERS.index("plant") for name in twin)


def test_the_rehearsal_uses_the_plant_only_through_run_operate_and_weigh() -> None:
    from transfertwin.rehearsal import _operations, _rehearse

    def named_plant(node: ast.AST) -> bool:
        return (isinstance(node, ast.Name) and node.id == "plant") or (
            isinstance(node, ast.Attribute) and node.attr == "plant"
        )

    used = set()
    for module in (_rehearse, _operations):
        tree = ast.parse(inspect.getsource(module))
        used |= {
            node.attr
            for node in ast.walk(tree)
            if isinstance(node, ast.Attribute) and named_plant(node.value)
        }
    assert used == {"run", "operate", "weigh"}


def test_weighing_is_a_noisy_reproducible_measurement_not_the_hidden_value() -> None:
    from transfertwin.plant._plant import _object_model

    a, b = EmulatedPlant(4).weigh("o3"), EmulatedPlant(4).weigh("o3")
    assert a == b  # the same reading for the same plant
    obj = draw_object(4, "o3")
    mass = _object_model(obj).mass
    true_kg = mass.mass_kg * obj.mass_scale
    true_com = [c + o for c, o in zip(mass.com_m, obj.com_offset_m, strict=True)]
    assert a.mass_kg != true_kg and abs(a.mass_kg - true_kg) < 0.02 * true_kg
    assert a.com_m != tuple(true_com)
    assert max(abs(x - y) for x, y in zip(a.com_m, true_com, strict=True)) < 0.005
    with pytest.raises(InputError, match="no object"):
        EmulatedPlant(4).weigh("o99")


def test_plant_features_are_compliant_and_a_named_station_is_used() -> None:
    assert all(0.03 <= draw_object(s, "o3").feature_solref[0] <= 0.08 for s in range(5))
    plant = EmulatedPlant(1)
    station = plant.stations[-1]
    req = PlantRequest("o3", "back", "both", 90, station)
    rows = plant.operate([req, req])
    assert [r["transfer_unit"] for r in rows] == [station, station]
    assert all(r["transfer_time_s"] > 0 for r in rows)
    assert set(rows[0]) == {*PLANT_COLUMNS, "transfer_time_s"}
    with pytest.raises(InputError, match="no station"):
        plant.run([PlantRequest("o3", "back", "both", 90, "TU_Z")])


def test_the_plant_takes_none_of_the_twins_contact_shortcuts() -> None:
    from transfertwin.plant._plant import _scene_config

    obj, scene = draw_object(3, "o3"), draw_scene(3)
    physics = _scene_config(scene, obj).physics
    assert physics.max_hulls is None and physics.multiccd is True
    assert physics.multiccd_for(40) and physics.guard
