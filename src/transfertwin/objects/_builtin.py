"""The 37 built-in cores o1..o37, read from package data (no CoACD at run time).

``transfertwin/data/cores`` holds, per core, ``oN.stl`` (binary STL, metres,
frame F_O), ``oN.hulls.npz`` (its CoACD hulls) and one ``manifest.json`` with the
SHA-256 of every file; ``scripts/make_cores.py`` makes them. A file whose hash
differs from the manifest is refused. ``features.json`` adds each core's resting
features (see `transfertwin.objects._features`; ``scripts/make_core_features.py``).
"""

from __future__ import annotations

import dataclasses
import functools
import hashlib
import json
import re
from importlib import resources
from typing import TYPE_CHECKING

from transfertwin.objects._core_draw import core_spec
from transfertwin.objects._core_spec import BUILTIN_COUNT
from transfertwin.objects._cores import mesh_from_stl_bytes
from transfertwin.objects._features import FEATURES_NAME, read_features
from transfertwin.objects._hulls import hulls_from_npz_bytes
from transfertwin.objects._mass import mass_properties
from transfertwin.objects._model import ObjectModel
from transfertwin.objects._proxy import Protrusion, ProxySpec, proxy_model
from transfertwin.objects._stl import mesh_content_hash

if TYPE_CHECKING:
    from importlib.resources.abc import Traversable

__all__ = [
    "MANIFEST_NAME",
    "BuiltinDataError",
    "builtin_features",
    "builtin_ids",
    "cores_data_dir",
    "features_version",
    "is_builtin_id",
    "load_builtin",
    "load_builtin_from",
]

MANIFEST_NAME = "manifest.json"
_ID_PATTERN = re.compile(r"o([1-9][0-9]*)")


class BuiltinDataError(RuntimeError):
    """Shipped core data is missing or does not match its manifest (broken install)."""


def builtin_ids() -> list[str]:
    """Ids of the built-in cores: ``["o1", ..., "o37"]``."""
    return [f"o{i}" for i in range(1, BUILTIN_COUNT + 1)]


def is_builtin_id(ref: object) -> bool:
    """True if ``ref`` is the string ``"o1"``..``"o37"``."""
    if not isinstance(ref, str):
        return False
    match = _ID_PATTERN.fullmatch(ref)
    return match is not None and int(match.group(1)) <= BUILTIN_COUNT


def cores_data_dir() -> Traversable:
    """Package-data directory of the built-in cores."""
    return resources.files("transfertwin").joinpath("data", "cores")


@functools.cache
def load_builtin(object_id: str, *, features: bool = True) -> ObjectModel:
    """Load a built-in core from package data (memoised: one instance per id).

    Args:
        object_id: ``"o1"``..``"o37"``.
        features: Add the core's shipped resting features (flange ears, studs: one
            protrusion per face, see `transfertwin.objects._features`); False gives the
            plain procedural body.

    Returns:
        The model; its mass is the core's specified mass.

    Raises:
        KeyError: If ``object_id`` is not a built-in id.
        BuiltinDataError: If the package data is missing or corrupt.
    """
    return load_builtin_from(cores_data_dir(), object_id, features=features)


def builtin_features(object_id: str) -> tuple[Protrusion, ...]:
    """The shipped resting features of built-in core ``object_id`` (empty if none listed)."""
    try:
        return _features_table().get(object_id, ())
    except ValueError as exc:
        raise BuiltinDataError(f"core data: {exc}") from exc


@functools.cache
def _features_table() -> dict[str, tuple[Protrusion, ...]]:
    return read_features(cores_data_dir())


@functools.cache
def features_version() -> str:
    """SHA-256 (first 16 hex digits) of the shipped ``features.json``; "none" without one.

    Study plans record it, so a store filled with other features is not resumed.
    """
    path = cores_data_dir().joinpath(FEATURES_NAME)
    if not path.is_file():
        return "none"
    return hashlib.sha256(path.read_bytes()).hexdigest()[:16]


def load_builtin_from(
    directory: Traversable, object_id: str, *, features: bool = True
) -> ObjectModel:
    """Load a built-in core from ``directory`` (not memoised), checking file hashes.

    Args:
        directory: Directory with ``manifest.json`` and the core files.
        object_id: ``"o1"``..``"o37"``.
        features: Add the resting features listed in the directory's ``features.json``.

    Returns:
        The model.

    Raises:
        KeyError: If ``object_id`` is not a built-in id.
        BuiltinDataError: If a file is missing or its SHA-256 differs from the manifest.
    """
    if not is_builtin_id(object_id):
        raise KeyError(object_id)
    entry = _read_manifest(directory)["cores"].get(object_id)
    if entry is None:
        raise BuiltinDataError(f"core data manifest has no entry for {object_id}")
    stl = _read_checked(directory, entry["stl"], entry["stl_sha256"])
    hulls = hulls_from_npz_bytes(_read_checked(directory, entry["hulls"], entry["hulls_sha256"]))
    mesh = mesh_from_stl_bytes(stl, f"{object_id}.stl")
    body = ObjectModel(
        object_id=object_id,
        mesh=mesh,
        hulls=hulls,
        mass=mass_properties(mesh, mass_kg=float(entry["mass_kg"])),
        source="builtin",
        content_hash=mesh_content_hash(mesh),
        spec=core_spec(int(entry["index"])),
    )
    if not features:
        return body
    try:
        prots = read_features(directory).get(object_id, ())
    except ValueError as exc:
        raise BuiltinDataError(f"core data: {exc}") from exc
    if not any(p.depth_m > 0 for p in prots):
        return body
    featured = proxy_model(body, ProxySpec(object_id, object_id, prots))
    return dataclasses.replace(featured, source="builtin", spec=body.spec)


def _read_manifest(directory: Traversable) -> dict:
    """Parse the manifest of ``directory``."""
    try:
        return json.loads(directory.joinpath(MANIFEST_NAME).read_text(encoding="utf-8"))
    except (OSError, ValueError) as exc:
        raise BuiltinDataError(f"cannot read core data manifest ({exc})") from exc


def _read_checked(directory: Traversable, name: str, sha256: str) -> bytes:
    """Read ``name`` and check its SHA-256 against the manifest."""
    try:
        data = directory.joinpath(name).read_bytes()
    except OSError as exc:
        raise BuiltinDataError(f"cannot read core data file {name} ({exc})") from exc
    actual = hashlib.sha256(data).hexdigest()
    if actual != sha256:
        raise BuiltinDataError(
            f"core data file {name} is corrupt: sha256 {actual[:12]}… != manifest {sha256[:12]}…"
        )
    return data
