"""The static 3-D scene of a replay, read from the compiled MuJoCo model.

Every geom of the units (belt decks, pulleys) with its type, size, colour and pose in its
body's frame, the bodies' poses (the TM is the world, the TU docked with the replay's
docking error and, as a ghost, at its nominal pose), the light barriers' beams, and the
object: its convex hulls (the collision geometry MuJoCo simulates) and its full mesh, both
in the object's body frame F_O. Meshes are float32 vertices and uint32 triangle indices.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import mujoco
import numpy as np

from transfertwin.objects import load_object
from transfertwin.sim import OBJECT_BODY, TU_BODY, VirtualTransferSystem, tu_quat

__all__ = ["GeomPart", "MeshData", "SceneGeometry", "scene_geometry"]

_TYPES = {
    int(mujoco.mjtGeom.mjGEOM_BOX): "box",
    int(mujoco.mjtGeom.mjGEOM_CYLINDER): "cylinder",
    int(mujoco.mjtGeom.mjGEOM_MESH): "mesh",
}


@dataclass(frozen=True)
class MeshData:
    """A triangle mesh: vertices (n, 3) float32 and faces (m, 3) uint32."""

    vertices: np.ndarray
    faces: np.ndarray


@dataclass(frozen=True)
class GeomPart:
    """One geom in its body's frame ('world', 'tu' or 'object').

    `size` is MuJoCo's (box: half extents; cylinder: radius, half length along z); a mesh
    geom's triangles are `mesh`.
    """

    name: str
    body: str
    kind: str
    size: tuple[float, float, float]
    pos: tuple[float, float, float]
    quat: tuple[float, float, float, float]
    rgba: tuple[float, float, float, float]
    mesh: MeshData | None = None


@dataclass(frozen=True)
class SceneGeometry:
    """Everything static of a replay's scene (see the module doc)."""

    parts: tuple[GeomPart, ...]
    barriers: tuple[tuple[str, str, tuple[float, ...], tuple[float, ...]], ...]
    beam_m: float
    tu_pos: tuple[float, float, float]
    tu_quat: tuple[float, float, float, float]
    nominal_tu_pos: tuple[float, float, float]
    nominal_tu_quat: tuple[float, float, float, float]
    floor_z: float
    object_mesh: MeshData
    tm_length_m: float
    tu_length_m: float
    belt_half_span_m: float


def _tuple(values: np.ndarray) -> tuple[float, ...]:
    return tuple(float(v) for v in values)


def _mesh(model: mujoco.MjModel, mesh_id: int) -> MeshData:
    v0, nv = int(model.mesh_vertadr[mesh_id]), int(model.mesh_vertnum[mesh_id])
    f0, nf = int(model.mesh_faceadr[mesh_id]), int(model.mesh_facenum[mesh_id])
    return MeshData(
        np.asarray(model.mesh_vert[v0 : v0 + nv], dtype=np.float32),
        np.asarray(model.mesh_face[f0 : f0 + nf], dtype=np.uint32),
    )


def scene_geometry(
    system: VirtualTransferSystem,
    object_ref: str,
    units: str,
    tu_pose: tuple[float, float, float],
) -> SceneGeometry:
    """The static scene of `system` with the TU docked at `tu_pose` (x, y, yaw)."""
    model = system.model
    bodies = {0: "world", model.body(TU_BODY).id: "tu", model.body(OBJECT_BODY).id: "object"}
    parts: list[GeomPart] = []
    floor_z = 0.0
    for g in range(model.ngeom):
        gtype = int(model.geom_type[g])
        if gtype == int(mujoco.mjtGeom.mjGEOM_PLANE):
            floor_z = float(model.geom_pos[g][2])
            continue
        kind = _TYPES.get(gtype)
        body = bodies.get(int(model.geom_bodyid[g]))
        if kind is None or body is None:
            continue
        mesh = _mesh(model, int(model.geom_dataid[g])) if kind == "mesh" else None
        parts.append(GeomPart(
            model.geom(g).name, body, kind, _tuple(model.geom_size[g]),
            _tuple(model.geom_pos[g]), _tuple(model.geom_quat[g]), _tuple(model.geom_rgba[g]),
            mesh,
        ))  # fmt: skip
    barriers = tuple(
        (model.site(s).name, bodies.get(int(model.site_bodyid[s]), "world"),
         _tuple(model.site_pos[s]), _tuple(model.site_quat[s]))
        for s in range(model.nsite)
    )  # fmt: skip
    layout = system.cfg.layout
    pitch, roll = math.radians(layout.tu_pitch_deg), math.radians(layout.tu_roll_deg)
    x, y, yaw = tu_pose
    obj = load_object(object_ref, units=units)
    return SceneGeometry(
        parts=tuple(parts), barriers=barriers,
        beam_m=2 * layout.belt_width_m + layout.belt_separation_m,
        tu_pos=(x, y, layout.tu_height_offset_m), tu_quat=_tuple(tu_quat(yaw, pitch, roll)),
        nominal_tu_pos=(float(system.cfg.gap_m), 0.0, layout.tu_height_offset_m),
        nominal_tu_quat=_tuple(tu_quat(0.0, pitch, roll)), floor_z=floor_z,
        object_mesh=MeshData(np.asarray(obj.mesh.vertices, dtype=np.float32),
                             np.asarray(obj.mesh.faces, dtype=np.uint32)),
        tm_length_m=layout.tm_length_m, tu_length_m=layout.tu_length_m,
        belt_half_span_m=layout.belt_width_m + 0.5 * layout.belt_separation_m,
    )  # fmt: skip
