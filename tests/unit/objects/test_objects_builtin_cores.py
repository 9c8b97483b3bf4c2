"""Built-in cores o1..o37: shipped data, F_O convention, regeneration, integrity."""

from __future__ import annotations

import dataclasses
import hashlib
import json
import shutil
from pathlib import Path

import numpy as np
import pytest
from scipy.spatial import ConvexHull

from transfertwin import InputError
from transfertwin.objects import (
    BuiltinDataError,
    ObjectModel,
    builtin_ids,
    core_spec,
    generate_core,
    load_builtin,
    load_object,
)
from transfertwin.objects._builtin import cores_data_dir, load_builtin_from
from transfertwin.objects._cores import core_stl_bytes

IDS = builtin_ids()
CORES_DIR = Path(str(cores_data_dir()))
MANIFEST = json.loads((CORES_DIR / "manifest.json").read_text())
CONTACT_TOL_M = 0.0002  # the housing sits 0.4 mm inside the can's support planes


@pytest.fixture(scope="module")
def models() -> dict[str, ObjectModel]:
    return {object_id: load_object(object_id) for object_id in IDS}


def test_builtin_ids_are_o1_to_o37() -> None:
    assert builtin_ids() == [f"o{i}" for i in range(1, 38)]


def test_unknown_id_is_rejected_with_one_clear_line() -> None:
    with pytest.raises(InputError) as exc:
        load_object("o99")
    assert str(exc.value) == (
        "unknown object 'o99': expected o1..o37 or a path to an STL/OBJ/PLY mesh"
    )


@pytest.mark.parametrize("ref", ["o0", "o38", "O1", "core1"])
def test_near_miss_ids_are_unknown(ref: str) -> None:
    with pytest.raises(InputError, match=f"unknown object '{ref}'"):
        load_object(ref)


def test_builtin_loading_is_memoised(models: dict[str, ObjectModel]) -> None:
    assert load_object("o4") is models["o4"]


def test_mass_override_keeps_mesh_and_hulls(models: dict[str, ObjectModel]) -> None:
    heavy = load_object("o4", mass_kg=10.0)
    assert heavy.mass.mass_kg == pytest.approx(10.0)
    assert heavy.hulls is models["o4"].hulls
    assert models["o4"].mass.mass_kg == MANIFEST["cores"]["o4"]["mass_kg"]


def test_all_37_meshes_are_distinct(models: dict[str, ObjectModel]) -> None:
    assert len({m.content_hash for m in models.values()}) == 37
    assert len({e["stl_sha256"] for e in MANIFEST["cores"].values()}) == 37


@pytest.mark.parametrize("object_id", IDS)
def test_builtin_core_is_a_starter_sized_closed_volume(
    models: dict[str, ObjectModel], object_id: str
) -> None:
    model = models[object_id]
    mesh = model.mesh
    assert model.source == "builtin" and model.object_id == object_id
    assert mesh.is_watertight and mesh.is_volume
    assert 0.18 <= mesh.extents[0] <= 0.26  # overall length along x
    assert 2.0 <= model.mass.mass_kg <= 5.0
    assert 2000 <= model.mass.mass_kg / mesh.volume <= 4500  # effective density, kg/m^3
    np.testing.assert_allclose(model.mass.com_m, 0.0, atol=1e-6)  # F_O origin at the COM
    assert 1000 <= len(mesh.faces) <= 8000


@pytest.mark.parametrize("object_id", IDS)
def test_builtin_hulls_approximate_the_mesh(object_id: str) -> None:
    model = load_builtin(object_id, features=False)  # the body's CoACD hulls alone
    entry = MANIFEST["cores"][object_id]
    assert 1 <= len(model.hulls) == entry["n_hulls"] <= entry["coacd"]["max_convex_hull"]
    points = np.vstack(model.hulls)
    lo, hi = model.mesh.bounds
    assert np.all(points >= lo - 0.003) and np.all(points <= hi + 0.003)
    hull_volume = sum(ConvexHull(h).volume for h in model.hulls)
    assert hull_volume == pytest.approx(model.mesh.volume, rel=0.25)


def _support(mesh_vertices: np.ndarray, face: str) -> np.ndarray:
    """Vertices touching the ground when lying on ``face`` (F_O coordinates)."""
    z = mesh_vertices[:, 2] if face == "front" else -mesh_vertices[:, 2]
    return mesh_vertices[z <= z.min() + CONTACT_TOL_M]


def _pinion_axis_y(vertices: np.ndarray) -> float:
    tip = vertices[vertices[:, 0] >= vertices[:, 0].max() - 0.005]
    return float((tip[:, 1].min() + tip[:, 1].max()) / 2.0)


@pytest.mark.parametrize("object_id", IDS)
def test_pinion_is_a_narrow_feature_at_plus_x(
    models: dict[str, ObjectModel], object_id: str
) -> None:
    vertices = models[object_id].mesh.vertices
    tip = vertices[vertices[:, 0] >= vertices[:, 0].max() - 0.005]
    tip_width = np.ptp(tip[:, 1:], axis=0).max()
    assert tip_width <= 0.04  # pinion Ø <= 40 mm
    assert tip_width < 0.6 * np.ptp(vertices[:, 2])  # much narrower than the can


@pytest.mark.parametrize("object_id", IDS)
@pytest.mark.parametrize("face", ["front", "back"])
def test_can_and_solenoid_side_carry_the_core_on_both_faces(
    models: dict[str, ObjectModel], object_id: str, face: str
) -> None:
    vertices = models[object_id].mesh.vertices
    axis_y = _pinion_axis_y(vertices)  # the pinion is coaxial with the can
    contact = _support(vertices, face)
    y = contact[:, 1] if face == "front" else -contact[:, 1]
    axis = axis_y if face == "front" else -axis_y
    # the can touches along its axis line; the solenoid side (-y on 'front', +y on 'back'
    # after turning over) touches at least 40 mm further out; nothing touches on the other
    # side of the can beyond the flat facet around its support line (5 mm)
    assert np.any(np.abs(y - axis) < 0.002)
    assert (y.min() < axis - 0.04) if face == "front" else (y.max() > axis + 0.04)
    assert (y.max() < axis + 0.005) if face == "front" else (y.min() > axis - 0.005)


@pytest.mark.parametrize("object_id", IDS)
@pytest.mark.parametrize("face", ["front", "back"])
def test_centre_of_mass_lies_inside_the_support_polygon(
    models: dict[str, ObjectModel], object_id: str, face: str
) -> None:
    contact = _support(models[object_id].mesh.vertices, face)[:, :2]
    hull = ConvexHull(contact)
    # signed distances of the COM (origin) to the hull's edges: all inside by >= 10 mm
    offsets = hull.equations[:, 2]
    assert np.all(offsets <= -0.010)


def _generator_versions_match() -> bool:
    """Whether the geometry libraries are the ones the shipped data was made with."""
    from importlib.metadata import version

    recorded = MANIFEST["versions"]
    return all(version(name) == recorded[name] for name in ("manifold3d", "numpy", "trimesh"))


@pytest.mark.parametrize("index", [1, 4, 22, 37])
def test_regenerating_a_core_gives_the_shipped_mesh(
    models: dict[str, ObjectModel], index: int
) -> None:
    object_id = f"o{index}"
    shipped_mesh = models[object_id].mesh
    mesh = generate_core(index)
    if _generator_versions_match():
        # Same libraries: bit-for-bit the shipped bytes.
        shipped = (CORES_DIR / f"{object_id}.stl").read_bytes()
        regenerated = core_stl_bytes(index)
        assert hashlib.sha256(regenerated).hexdigest() == MANIFEST["cores"][object_id]["stl_sha256"]
        assert regenerated == shipped
        np.testing.assert_array_equal(mesh.vertices, shipped_mesh.vertices)
        np.testing.assert_array_equal(mesh.faces, shipped_mesh.faces)
    else:
        # Newer boolean/numeric libraries may order or round vertices differently: the
        # same solid within 0.1 mm and 0.5 % volume. (The shipped files stay authoritative.)
        np.testing.assert_allclose(mesh.bounds, shipped_mesh.bounds, atol=1e-4)
        assert mesh.volume == pytest.approx(shipped_mesh.volume, rel=5e-3)
        assert mesh.is_watertight


def test_manifest_specs_match_the_generator(models: dict[str, ObjectModel]) -> None:
    for object_id, entry in MANIFEST["cores"].items():
        spec = core_spec(entry["index"])
        shipped = json.loads(json.dumps(dataclasses.asdict(spec)))
        assert entry["spec"] == shipped
        assert entry["mass_kg"] == spec.mass_kg
        assert models[object_id].spec == spec


def test_tampered_stl_is_refused(tmp_path: Path) -> None:
    data = tmp_path / "cores"
    shutil.copytree(CORES_DIR, data)
    stl = bytearray((data / "o2.stl").read_bytes())
    stl[200] ^= 0x01
    (data / "o2.stl").write_bytes(bytes(stl))
    with pytest.raises(BuiltinDataError, match=r"o2\.stl is corrupt"):
        load_builtin_from(data, "o2")
    assert load_builtin_from(data, "o3").object_id == "o3"


def test_shipped_data_is_small() -> None:
    total = sum(p.stat().st_size for p in CORES_DIR.iterdir())
    assert total < 15e6
