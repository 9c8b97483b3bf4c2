"""`load_object` with a user mesh end to end, and `export_object`."""

from __future__ import annotations

from pathlib import Path

import coacd
import numpy as np
import pytest
import trimesh
from manifold3d import Manifold

from transfertwin import InputError
from transfertwin.objects import (
    DEFAULT_DENSITY_KG_M3,
    MeshError,
    export_object,
    load_mesh,
    load_object,
)


def _bracket_mm() -> trimesh.Trimesh:
    """T-shaped bracket in millimetres: 120 × 30 × 20 bar on a 30 × 30 × 60 post."""
    solid = Manifold.cube((120.0, 30.0, 20.0)) + Manifold.cube((30.0, 30.0, 60.0)).translate(
        (45.0, 0.0, 0.0)
    )
    raw = solid.to_mesh64()
    return trimesh.Trimesh(np.asarray(raw.vert_properties)[:, :3], np.asarray(raw.tri_verts))


BRACKET_VOLUME_M3 = (120 * 30 * 20 + 30 * 30 * 40) * 1e-9


@pytest.fixture(scope="module")
def bracket_path(tmp_path_factory: pytest.TempPathFactory) -> Path:
    path = tmp_path_factory.mktemp("meshes") / "bracket.stl"
    _bracket_mm().export(path)
    return path


def test_user_mesh_end_to_end(
    bracket_path: Path, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    model = load_object(bracket_path, units="mm", cache_dir=tmp_path)
    assert model.object_id == "bracket"
    assert model.source == str(bracket_path)
    assert model.spec is None and not model.is_builtin
    np.testing.assert_allclose(model.mesh.extents, [0.12, 0.03, 0.06], rtol=1e-6)
    np.testing.assert_allclose(model.mesh.center_mass, 0.0, atol=1e-9)  # origin at the COM
    assert model.mass.mass_kg == pytest.approx(DEFAULT_DENSITY_KG_M3 * BRACKET_VOLUME_M3)
    assert len(model.hulls) >= 2
    assert len(list(tmp_path.glob("*.npz"))) == 1

    def fail(*_args: object, **_kwargs: object) -> None:
        raise AssertionError("CoACD must not run on a cache hit")

    monkeypatch.setattr(coacd, "run_coacd", fail)
    again = load_object(bracket_path, units="mm", cache_dir=tmp_path, mass_kg=1.5)
    assert again.content_hash == model.content_hash
    assert again.mass.mass_kg == pytest.approx(1.5)
    for a, b in zip(model.hulls, again.hulls, strict=True):
        np.testing.assert_array_equal(a, b)


def test_user_mesh_with_density(bracket_path: Path, tmp_path: Path) -> None:
    model = load_object(bracket_path, units="mm", cache_dir=tmp_path, density_kg_m3=2700.0)
    assert model.mass.mass_kg == pytest.approx(2700.0 * BRACKET_VOLUME_M3)


def test_invalid_mass_is_rejected_before_decomposition(bracket_path: Path, tmp_path: Path) -> None:
    with pytest.raises(InputError, match="mass_kg"):
        load_object(bracket_path, units="mm", cache_dir=tmp_path, mass_kg=-1.0)
    assert not list(tmp_path.iterdir())


def test_missing_mesh_file_is_a_mesh_error(tmp_path: Path) -> None:
    with pytest.raises(MeshError, match="no such file"):
        load_object(tmp_path / "nothing.stl")


def test_existing_file_with_other_suffix_is_a_mesh_error(tmp_path: Path) -> None:
    path = tmp_path / "notes.txt"
    path.write_text("hello")
    with pytest.raises(MeshError, match="unsupported mesh format"):
        load_object(path)


def test_export_builtin_round_trips(tmp_path: Path) -> None:
    out = export_object("o3", tmp_path / "o3.stl")
    assert out == tmp_path / "o3.stl"
    exported = load_mesh(out)
    original = load_object("o3").mesh
    np.testing.assert_allclose(exported.bounds, original.bounds, atol=1e-9)
    assert exported.volume == pytest.approx(original.volume, rel=1e-9)
    assert [p.name for p in tmp_path.iterdir()] == ["o3.stl"]


def test_export_user_mesh_in_metres(bracket_path: Path, tmp_path: Path) -> None:
    out = export_object(bracket_path, tmp_path / "bracket_m.stl", units="mm")
    np.testing.assert_allclose(load_mesh(out).extents, [0.12, 0.03, 0.06], rtol=1e-6)


@pytest.mark.parametrize("name", ["o3.obj", "o3"])
def test_export_requires_stl_suffix(tmp_path: Path, name: str) -> None:
    with pytest.raises(InputError, match=r"must end in \.stl"):
        export_object("o3", tmp_path / name)
    assert not list(tmp_path.iterdir())


def test_export_requires_existing_directory(tmp_path: Path) -> None:
    with pytest.raises(InputError, match="does not exist"):
        export_object("o3", tmp_path / "missing" / "o3.stl")


def test_export_unknown_object_writes_nothing(tmp_path: Path) -> None:
    with pytest.raises(InputError, match="unknown object 'o99'"):
        export_object("o99", tmp_path / "o99.stl")
    assert not list(tmp_path.iterdir())
