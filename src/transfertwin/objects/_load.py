"""`load_object` and `export_object`: built-in core ids or user mesh files."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import trimesh

from transfertwin._errors import InputError
from transfertwin.objects._builtin import builtin_ids, is_builtin_id, load_builtin
from transfertwin.objects._hulls import (
    coacd_params,
    decompose_hulls,
    default_cache_dir,
    hull_cache_key,
)
from transfertwin.objects._mass import mass_properties
from transfertwin.objects._mesh import MESH_SUFFIXES, load_mesh
from transfertwin.objects._model import ObjectModel
from transfertwin.objects._proxy import PROXY_SUFFIX, proxy_model, read_proxy
from transfertwin.objects._stl import mesh_content_hash, write_stl

__all__ = ["export_object", "hull_cache_path", "load_object"]


def load_object(
    ref: str | Path,
    *,
    units: str = "m",
    mass_kg: float | None = None,
    density_kg_m3: float | None = None,
    cache_dir: Path | None = None,
) -> ObjectModel:
    """Load a built-in core or a user mesh as an `ObjectModel`.

    ``"o1"``..``"o37"`` are the built-in cores (shipped mesh and hulls, mass from
    their spec; memoised). A ``*.proxy.json`` file is a calibrated proxy (see
    `transfertwin.objects.ProxySpec`): its base object plus protrusion hulls.
    Anything else is a path to an STL/OBJ/PLY file: it is loaded with
    `load_mesh`, shifted so that its centre of mass is the origin, and decomposed
    with `decompose_hulls` (cached in ``cache_dir``). Its axes must already follow
    F_O (+x to the pinion, +z up on face 'front').

    Args:
        ref: Built-in id, or path to a mesh file. A built-in id wins over a
            file of the same name.
        units: Units of a mesh file (``"m"``, ``"cm"``, ``"mm"``, ``"in"``);
            ignored for built-in cores, which are in metres.
        mass_kg: Mass override in kg (exclusive with ``density_kg_m3``).
        density_kg_m3: Uniform density in kg/m^3; for user meshes without
            either, `DEFAULT_DENSITY_KG_M3`.
        cache_dir: Hull cache directory for user meshes (default: see
            `decompose_hulls`).

    Returns:
        The object model.

    Raises:
        InputError: If ``ref`` is neither a built-in id nor a mesh path, or a
            mass/density is invalid.
        MeshError: If the mesh file is unusable (see `load_mesh`).
    """
    if str(ref).endswith(PROXY_SUFFIX):
        spec = read_proxy(ref)
        if is_builtin_id(spec.base):  # the plain body: the proxy's features replace the shipped
            base = _with_mass(load_builtin(spec.base, features=False), mass_kg, density_kg_m3)
        elif spec.base.endswith(PROXY_SUFFIX):
            base = load_object(spec.base, mass_kg=mass_kg, density_kg_m3=density_kg_m3)
        else:  # a mesh path relative to the proxy file
            mesh = Path(ref).parent / spec.base
            base = load_object(mesh, units=units, mass_kg=mass_kg, density_kg_m3=density_kg_m3,
                               cache_dir=cache_dir)  # fmt: skip
        return proxy_model(base, spec)
    if is_builtin_id(ref):
        return _with_mass(load_builtin(str(ref)), mass_kg, density_kg_m3)
    path = _mesh_path(ref)
    mesh = _centred(load_mesh(path, units))
    mass = mass_properties(mesh, mass_kg=mass_kg, density_kg_m3=density_kg_m3)
    hulls = decompose_hulls(mesh, cache_dir=cache_dir)
    return ObjectModel(
        object_id=path.stem,
        mesh=mesh,
        hulls=hulls,
        mass=mass,
        source=str(path),
        content_hash=mesh_content_hash(mesh),
    )


def hull_cache_path(
    ref: str | Path, *, units: str = "m", cache_dir: Path | None = None
) -> Path | None:
    """Where `load_object` keeps the CoACD hulls of a user mesh (exists once computed).

    Lets a command say, before the first `load_object` of a mesh, that the decomposition
    (seconds to minutes) runs now, once. None for a built-in core or a proxy of one (their
    hulls are shipped); a proxy over a mesh file gives that mesh's path.

    Raises:
        InputError, MeshError: As `load_object` for an unusable reference.
    """
    if str(ref).endswith(PROXY_SUFFIX):
        spec = read_proxy(ref)
        if is_builtin_id(spec.base):
            return None
        base = spec.base if spec.base.endswith(PROXY_SUFFIX) else Path(ref).parent / spec.base
        return hull_cache_path(base, units=units, cache_dir=cache_dir)
    if is_builtin_id(ref):
        return None
    mesh = _centred(load_mesh(_mesh_path(ref), units))
    directory = Path(cache_dir) if cache_dir is not None else default_cache_dir()
    return directory / f"{hull_cache_key(mesh, coacd_params(0.05, 24, 0))}.npz"


def export_object(ref: str | Path, out_path: str | Path, *, units: str = "m") -> Path:
    """Write an object's mesh (frame F_O, metres) as binary STL.

    Args:
        ref: Built-in id or mesh path, as for `load_object`.
        out_path: Destination ``.stl`` file; its directory must exist. Written
            atomically: on failure no partial file is left.
        units: Units of a mesh file given as ``ref``.

    Returns:
        The written path.

    Raises:
        InputError: If ``ref`` is unknown, ``out_path`` is not a writable
            ``.stl`` path, or the mesh file is unusable.
    """
    out = Path(out_path)
    if out.suffix.lower() != ".stl":
        raise InputError(f"{out}: export writes STL; the output file must end in .stl")
    if not out.parent.is_dir():
        raise InputError(f"{out}: directory {out.parent} does not exist")
    if is_builtin_id(ref):
        mesh = load_builtin(str(ref)).mesh
    else:
        mesh = _centred(load_mesh(_mesh_path(ref), units))
    try:
        write_stl(mesh, out)
    except OSError as exc:
        raise InputError(f"{out}: cannot write file ({exc.strerror or exc})") from exc
    return out


def _with_mass(
    model: ObjectModel, mass_kg: float | None, density_kg_m3: float | None
) -> ObjectModel:
    """``model`` with its mass overridden, if either override is given."""
    if mass_kg is None and density_kg_m3 is None:
        return model
    mass = mass_properties(model.mesh, mass_kg=mass_kg, density_kg_m3=density_kg_m3)
    return dataclasses.replace(model, mass=mass)


def _mesh_path(ref: object) -> Path:
    """Path of a user mesh, or InputError for an unknown object reference."""
    if not isinstance(ref, (str, Path)):
        raise InputError(f"object reference must be an id or a path, got {type(ref).__name__}")
    path = Path(ref)
    if path.suffix.lower() in MESH_SUFFIXES or path.is_file():
        return path
    ids = builtin_ids()
    raise InputError(
        f"unknown object '{ref}': expected {ids[0]}..{ids[-1]} or a path to an STL/OBJ/PLY mesh"
    )


def _centred(mesh: trimesh.Trimesh) -> trimesh.Trimesh:
    """Shift ``mesh`` in place so that its centre of mass is the origin."""
    mesh.apply_translation(-mesh.center_mass)
    return mesh
