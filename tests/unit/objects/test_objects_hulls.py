"""`decompose_hulls`: CoACD output shape, on-disk cache by content hash."""

from __future__ import annotations

from pathlib import Path

import coacd
import numpy as np
import pytest
import trimesh
from manifold3d import Manifold
from scipy.spatial import ConvexHull

from transfertwin import InputError
from transfertwin._atomic import write_bytes_atomic, write_bytes_exclusive
from transfertwin.objects import _hulls, decompose_hulls, default_cache_dir


def _l_shape() -> trimesh.Trimesh:
    """L-shaped block, 0.12 × 0.08 × 0.04 m, volume 0.12·0.04·0.04 + 0.04·0.04·0.04 m³."""
    solid = Manifold.cube((0.12, 0.04, 0.04)) + Manifold.cube((0.04, 0.08, 0.04))
    raw = solid.to_mesh64()
    return trimesh.Trimesh(np.asarray(raw.vert_properties)[:, :3], np.asarray(raw.tri_verts))


def _forbid_coacd(monkeypatch: pytest.MonkeyPatch) -> None:
    def fail(*_args: object, **_kwargs: object) -> None:
        raise AssertionError("CoACD must not run on a cache hit")

    monkeypatch.setattr(coacd, "run_coacd", fail)


@pytest.fixture(scope="module")
def l_hulls(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, tuple[np.ndarray, ...]]:
    cache = tmp_path_factory.mktemp("hull_cache")
    return cache, decompose_hulls(_l_shape(), cache_dir=cache, threshold=0.05)


def test_hulls_are_k_by_3_float_arrays_covering_the_l_shape(l_hulls: tuple) -> None:
    _, hulls = l_hulls
    assert len(hulls) >= 2  # an L is not convex
    for hull in hulls:
        assert hull.dtype == np.float64
        assert hull.ndim == 2 and hull.shape[1] == 3 and len(hull) >= 4
        assert not hull.flags.writeable
    points = np.vstack(hulls)
    np.testing.assert_allclose(points.min(axis=0), [0, 0, 0], atol=2e-3)
    np.testing.assert_allclose(points.max(axis=0), [0.12, 0.08, 0.04], atol=2e-3)
    expected_volume = 0.12 * 0.04 * 0.04 + 0.04 * 0.04 * 0.04
    total = sum(ConvexHull(h).volume for h in hulls)
    assert total == pytest.approx(expected_volume, rel=0.15)


def test_second_call_hits_the_cache_without_running_coacd(
    l_hulls: tuple, monkeypatch: pytest.MonkeyPatch
) -> None:
    cache, first = l_hulls
    assert len(list(cache.glob("*.npz"))) == 1
    _forbid_coacd(monkeypatch)
    second = decompose_hulls(_l_shape(), cache_dir=cache, threshold=0.05)
    assert len(second) == len(first)
    for a, b in zip(first, second, strict=True):
        np.testing.assert_array_equal(a, b)


def test_other_parameters_miss_the_cache(l_hulls: tuple, monkeypatch: pytest.MonkeyPatch) -> None:
    cache, _ = l_hulls
    _forbid_coacd(monkeypatch)
    with pytest.raises(AssertionError, match="must not run"):
        decompose_hulls(_l_shape(), cache_dir=cache, threshold=0.06)
    with pytest.raises(AssertionError, match="must not run"):
        decompose_hulls(_l_shape(), cache_dir=cache, threshold=0.05, seed=1)


def test_moved_mesh_misses_the_cache(l_hulls: tuple, monkeypatch: pytest.MonkeyPatch) -> None:
    cache, _ = l_hulls
    moved = _l_shape()
    moved.apply_translation((1e-6, 0.0, 0.0))
    _forbid_coacd(monkeypatch)
    with pytest.raises(AssertionError, match="must not run"):
        decompose_hulls(moved, cache_dir=cache, threshold=0.05)


def test_corrupt_cache_file_is_recomputed(tmp_path: Path) -> None:
    box = trimesh.creation.box(extents=(0.05, 0.05, 0.05))
    decompose_hulls(box, cache_dir=tmp_path)
    (cache_file,) = tmp_path.glob("*.npz")
    cache_file.write_bytes(b"not a zip file")
    hulls = decompose_hulls(box, cache_dir=tmp_path)
    assert len(hulls) == 1
    np.testing.assert_allclose(np.abs(hulls[0]), 0.025, atol=1e-9)
    assert cache_file.read_bytes()[:2] == b"PK"  # rewritten as a zip (.npz)


def test_cache_leaves_no_temporary_files(tmp_path: Path) -> None:
    decompose_hulls(trimesh.creation.box(extents=(0.05, 0.05, 0.05)), cache_dir=tmp_path)
    assert [p.suffix for p in tmp_path.iterdir()] == [".npz"]


def test_default_cache_dir_follows_environment(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setenv("TRANSFERTWIN_CACHE", str(tmp_path))
    assert default_cache_dir() == tmp_path / "hulls"
    monkeypatch.delenv("TRANSFERTWIN_CACHE")
    monkeypatch.setenv("HOME", str(tmp_path / "home"))
    assert default_cache_dir() == tmp_path / "home" / ".cache" / "transfertwin" / "hulls"


@pytest.mark.parametrize(
    "kwargs",
    [{"threshold": 0.0}, {"threshold": 1.5}, {"max_hulls": 0}, {"max_hulls": 2.5}, {"seed": -1}],
)
def test_invalid_parameters_are_rejected(tmp_path: Path, kwargs: dict) -> None:
    box = trimesh.creation.box(extents=(0.05, 0.05, 0.05))
    with pytest.raises(InputError):
        decompose_hulls(box, cache_dir=tmp_path, **kwargs)


def test_concurrent_first_writer_wins(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """If another process stores hulls while CoACD runs here, its hulls are returned."""
    box = trimesh.creation.box(extents=(0.05, 0.05, 0.05))
    winner = (np.array([[0, 0, 0], [0.05, 0, 0], [0, 0.05, 0], [0, 0, 0.05]], dtype=float),)
    ours = (np.array([[0, 0, 0], [0.04, 0, 0], [0, 0.04, 0], [0, 0, 0.04]], dtype=float),)

    def racing_coacd(mesh: trimesh.Trimesh, params: dict) -> tuple[np.ndarray, ...]:
        path = tmp_path / f"{_hulls.hull_cache_key(mesh, params)}.npz"
        path.write_bytes(_hulls.hulls_to_npz_bytes(winner, params))
        return ours

    monkeypatch.setattr(_hulls, "coacd_hulls", racing_coacd)
    hulls = decompose_hulls(box, cache_dir=tmp_path)
    np.testing.assert_array_equal(hulls[0], winner[0])
    assert len(list(tmp_path.iterdir())) == 1


def test_write_bytes_exclusive_creates_once(tmp_path: Path) -> None:
    target = tmp_path / "file.bin"
    assert write_bytes_exclusive(target, b"first")
    assert not write_bytes_exclusive(target, b"second")
    assert target.read_bytes() == b"first"
    write_bytes_atomic(target, b"third")
    assert target.read_bytes() == b"third"
    assert [p.name for p in tmp_path.iterdir()] == ["file.bin"]


def test_write_atomic_sets_the_mode_before_any_byte_is_written(tmp_path):
    import stat

    from transfertwin._atomic import write_atomic

    secret = write_atomic(tmp_path / "secret.json", "{}", mode=0o600)
    public = write_atomic(tmp_path / "public.txt", b"x")
    assert stat.S_IMODE(secret.stat().st_mode) == 0o600
    assert stat.S_IMODE(public.stat().st_mode) == 0o644
    assert list(tmp_path.glob(".*.tmp")) == []
