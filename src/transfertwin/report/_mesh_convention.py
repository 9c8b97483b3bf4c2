"""How a user's mesh is put on the belt, in one sentence for the study report.

A mesh file is used as modelled (docs/design-choices.md, "Object frame, faces and
placement"; the picture ``docs/img/mesh-convention.png`` from
``scripts/make_mesh_convention.py``). The built-in cores follow the same rule; their x axis
points to the pinion, which the report already says. For a study with a user mesh the
report adds `mesh_convention_html`, so that 'front', 'back' and θ = 0 mean something
for a part the reader modelled.
"""

from __future__ import annotations

import html
from collections.abc import Mapping
from pathlib import PurePath

__all__ = ["MESH_CONVENTION", "MESH_SUFFIXES", "mesh_convention_html", "user_meshes"]

#: Suffixes of mesh files an object reference may name.
MESH_SUFFIXES = (".stl", ".obj", ".ply")
#: The convention, completing "A mesh is used as modelled: ...".
MESH_CONVENTION = (
    "the file's +x axis is the object's x axis; 'front' is the mesh lying as modelled, +z up "
    "(on its lowest side); 'back' is it turned over by 180° about x; at θ = 0 its +x points "
    "in the direction of travel TM → TU, θ counter-clockwise seen from above"
)


def user_meshes(params: Mapping[str, object]) -> tuple[str, ...]:
    """The mesh files among the study's objects (``plan.objects`` of the report's params)."""
    refs = params.get("plan.objects") or ()
    if isinstance(refs, str):
        refs = refs.split(",")
    return tuple(
        str(r) for r in refs  # type: ignore[union-attr]
        if PurePath(str(r)).suffix.lower() in MESH_SUFFIXES
    )  # fmt: skip


def mesh_convention_html(params: Mapping[str, object]) -> str:
    """One paragraph for a study with user meshes ('' without any)."""
    meshes = user_meshes(params)
    if not meshes:
        return ""
    names = ", ".join(f"<code>{html.escape(PurePath(m).name)}</code>" for m in meshes)
    return (
        f"<p class='lead'>Orientation of {names}: a mesh is used as modelled — "
        f"{html.escape(MESH_CONVENTION)}.</p>"
    )
