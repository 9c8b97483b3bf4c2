"""`load_mesh`: formats, units, rejection at the boundaries, repair."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import trimesh

from transfertwin import InputError
from transfertwin.objects import MeshError, load_mesh
from transfertwin.objects._stl import stl_bytes


def _cube(edge: float) -> trimesh.Trimesh:
    return trimesh.creation.box(extents=(edge, edge, edge))


def _write(mesh: trimesh.Trimesh, path: Path) -> Path:
    mesh.export(path)
    return path


def _assert_one_line(exc: pytest.ExceptionInfo, path: Path) -> None:
    message = str(exc.value)
    assert "\n" not in message
    assert str(path) in message


@pytest.mark.parametrize("suffix", [".stl", ".obj", ".ply"])
def test_load_mesh_reads_each_format_as_closed_volume(tmp_path: Path, suffix: str) -> None:
    path = _write(_cube(0.1), tmp_path / f"cube{suffix}")
    mesh = load_mesh(path)
    assert mesh.is_watertight
    assert mesh.volume == pytest.approx(1e-3, rel=1e-6)
    np.testing.assert_allclose(mesh.extents, [0.1, 0.1, 0.1], rtol=1e-6)


@pytest.mark.parametrize(
    ("units", "metres_per_unit"), [("m", 1.0), ("cm", 0.01), ("mm", 0.001), ("in", 0.0254)]
)
def test_load_mesh_converts_units_to_metres(
    tmp_path: Path, units: str, metres_per_unit: float
) -> None:
    path = _write(_cube(100.0 * 0.001 / metres_per_unit), tmp_path / "cube.stl")
    mesh = load_mesh(path, units=units)
    np.testing.assert_allclose(mesh.extents, [0.1, 0.1, 0.1], rtol=1e-6)


def test_load_mesh_100_mm_cube_in_mm_is_a_tenth_of_a_metre(tmp_path: Path) -> None:
    path = _write(_cube(100.0), tmp_path / "cube_mm.stl")
    assert load_mesh(path, units="mm").extents.max() == pytest.approx(0.1)


def test_load_mesh_rejects_unknown_units(tmp_path: Path) -> None:
    path = _write(_cube(0.1), tmp_path / "cube.stl")
    with pytest.raises(InputError, match="unknown units 'ft'"):
        load_mesh(path, units="ft")


def test_load_mesh_rejects_unsupported_suffix(tmp_path: Path) -> None:
    path = tmp_path / "part.step"
    path.write_text("ISO-10303-21;")
    with pytest.raises(MeshError, match="unsupported mesh format") as exc:
        load_mesh(path)
    _assert_one_line(exc, path)


def test_load_mesh_rejects_missing_file(tmp_path: Path) -> None:
    path = tmp_path / "missing.stl"
    with pytest.raises(MeshError, match="no such file") as exc:
        load_mesh(path)
    _assert_one_line(exc, path)


def test_load_mesh_rejects_corrupt_binary_stl(tmp_path: Path) -> None:
    path = tmp_path / "corrupt.stl"
    path.write_bytes(np.random.default_rng(7).bytes(1000))
    with pytest.raises(MeshError, match="corrupt") as exc:
        load_mesh(path)
    _assert_one_line(exc, path)


def test_load_mesh_rejects_truncated_binary_stl(tmp_path: Path) -> None:
    good = _write(_cube(0.1), tmp_path / "good.stl").read_bytes()
    path = tmp_path / "truncated.stl"
    path.write_bytes(good[:-20])
    with pytest.raises(MeshError, match="corrupt"):
        load_mesh(path)


def test_load_mesh_rejects_zero_byte_file(tmp_path: Path) -> None:
    path = tmp_path / "empty.stl"
    path.write_bytes(b"")
    with pytest.raises(MeshError) as exc:
        load_mesh(path)
    _assert_one_line(exc, path)


def test_load_mesh_rejects_stl_without_faces(tmp_path: Path) -> None:
    path = tmp_path / "nofaces.stl"
    path.write_bytes(b"x" * 80 + np.array([0], dtype="<u4").tobytes())
    with pytest.raises(MeshError, match="no faces") as exc:
        load_mesh(path)
    _assert_one_line(exc, path)


def test_load_mesh_rejects_obj_without_faces(tmp_path: Path) -> None:
    path = tmp_path / "points.obj"
    path.write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\n")
    with pytest.raises(MeshError, match="no faces"):
        load_mesh(path)


def test_load_mesh_rejects_nan_vertex(tmp_path: Path) -> None:
    cube = _cube(0.1)
    vertices = cube.vertices.copy()
    vertices[3, 0] = np.nan
    path = tmp_path / "nan.stl"
    path.write_bytes(stl_bytes(trimesh.Trimesh(vertices, cube.faces, process=False)))
    with pytest.raises(MeshError, match="non-finite") as exc:
        load_mesh(path)
    _assert_one_line(exc, path)


@pytest.mark.parametrize("edge_m", [0.005, 0.0099, 2.01, 3.0])
def test_load_mesh_rejects_size_outside_1_cm_to_2_m(tmp_path: Path, edge_m: float) -> None:
    path = _write(_cube(edge_m), tmp_path / "cube.stl")
    with pytest.raises(MeshError, match="outside") as exc:
        load_mesh(path)
    _assert_one_line(exc, path)


@pytest.mark.parametrize("edge_m", [0.0101, 1.99])
def test_load_mesh_accepts_size_just_inside_the_limits(tmp_path: Path, edge_m: float) -> None:
    path = _write(_cube(edge_m), tmp_path / "cube.stl")
    assert load_mesh(path).extents.max() == pytest.approx(edge_m, rel=1e-6)


def test_load_mesh_5_mm_cube_is_rejected_but_accepted_when_units_make_it_5_cm(
    tmp_path: Path,
) -> None:
    path = _write(_cube(5.0), tmp_path / "cube.stl")
    with pytest.raises(MeshError):
        load_mesh(path, units="mm")
    assert load_mesh(path, units="cm").extents.max() == pytest.approx(0.05)


def test_load_mesh_rejects_single_triangle(tmp_path: Path) -> None:
    triangle = trimesh.Trimesh([[0, 0, 0], [0.1, 0, 0], [0, 0.1, 0]], [[0, 1, 2]], process=False)
    path = _write(triangle, tmp_path / "triangle.stl")
    with pytest.raises(MeshError) as exc:
        load_mesh(path)
    _assert_one_line(exc, path)


def test_load_mesh_rejects_box_missing_three_sides(tmp_path: Path) -> None:
    cube = _cube(0.1)
    open_box = trimesh.Trimesh(cube.vertices, cube.faces[:6], process=False)  # 3 of 6 sides
    path = _write(open_box, tmp_path / "open_box.stl")
    with pytest.raises(MeshError, match="not a closed volume") as exc:
        load_mesh(path)
    _assert_one_line(exc, path)


def test_load_mesh_repairs_box_missing_one_triangle(tmp_path: Path) -> None:
    cube = _cube(0.1)
    holed = trimesh.Trimesh(cube.vertices, cube.faces[1:], process=False)
    assert not holed.is_watertight
    mesh = load_mesh(_write(holed, tmp_path / "holed.stl"))
    assert mesh.is_watertight
    assert mesh.volume == pytest.approx(1e-3, rel=1e-6)


def test_load_mesh_repairs_inside_out_mesh(tmp_path: Path) -> None:
    cube = _cube(0.1)
    inverted = trimesh.Trimesh(cube.vertices, cube.faces[:, ::-1], process=False)
    assert inverted.volume < 0
    mesh = load_mesh(_write(inverted, tmp_path / "inverted.stl"))
    assert mesh.volume == pytest.approx(1e-3, rel=1e-6)


def test_load_mesh_rejects_two_faces_glued_back_to_back(tmp_path: Path) -> None:
    sheet = trimesh.Trimesh(
        [[0, 0, 0], [0.1, 0, 0], [0, 0.1, 0]], [[0, 1, 2], [0, 2, 1]], process=False
    )
    path = _write(sheet, tmp_path / "sheet.stl")
    with pytest.raises(MeshError, match="no volume"):
        load_mesh(path)
