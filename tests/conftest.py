"""Shared fixtures: a user mesh on disk and an isolated hull cache."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import trimesh


@pytest.fixture(autouse=True)
def _isolated_cache(tmp_path_factory: pytest.TempPathFactory, monkeypatch: pytest.MonkeyPatch):
    """Every test writes hull caches into a per-session temporary folder."""
    cache = tmp_path_factory.getbasetemp() / "hull-cache"
    monkeypatch.setenv("TRANSFERTWIN_CACHE", str(cache))


@pytest.fixture(scope="session")
def box_stl(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A 200 x 90 x 80 mm box saved as an STL in millimetres."""
    path = tmp_path_factory.mktemp("meshes") / "box.stl"
    trimesh.creation.box(extents=(200.0, 90.0, 80.0)).export(path)
    return path


def box_hulls(ext=(0.2, 0.09, 0.08)) -> tuple[np.ndarray, ...]:
    """Corner vertices of a box centred at the origin (one convex hull), metres."""
    h = np.asarray(ext) / 2
    return (
        np.array(
            [
                [sx * h[0], sy * h[1], sz * h[2]]
                for sx in (-1, 1)
                for sy in (-1, 1)
                for sz in (-1, 1)
            ]
        ),
    )


def box_inertia(mass: float, ext=(0.2, 0.09, 0.08)) -> np.ndarray:
    """Inertia tensor (3, 3) of a solid box about its centre (analytic)."""
    a, b, c = ext
    m = mass / 12
    return np.diag([m * (b**2 + c**2), m * (a**2 + c**2), m * (a**2 + b**2)])


def plain_body_proxy(directory: Path, object_id: str = "o1") -> str:
    """Path of a proxy of built-in core `object_id` without protrusions: its plain body,
    for tests whose mechanism the core's shipped resting features would mask."""
    from transfertwin.objects import ProxySpec, write_proxy

    return str(
        write_proxy(ProxySpec(object_id, object_id, ()), directory / f"{object_id}.proxy.json")
    )
