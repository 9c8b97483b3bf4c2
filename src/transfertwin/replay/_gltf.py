"""A replay as an animated glTF 2.0 binary (.glb) that any glTF viewer opens.

trimesh builds the static scene (belt decks, pulleys, the TU where it docked, the light
barriers' beams, the object's mesh) and writes it as glTF; pygltflib then adds what trimesh
cannot write: one animation over the replay's samples — the object's translation and
rotation (linear), and each light barrier's red "interrupted" beam switched on and off by
its scale (step) — and a root node that turns F_T's z-up into glTF's y-up.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from transfertwin._atomic import write_atomic
from transfertwin.replay._payload import replay_geometry
from transfertwin.replay._record import BARRIER_NAMES, Replay
from transfertwin.replay._scene import SceneGeometry

__all__ = ["glb_bytes", "write_glb"]

_BEAM_RADIUS_M = 0.0025


def _matrix(pos: tuple[float, ...], quat_wxyz: tuple[float, ...]) -> np.ndarray:
    import trimesh

    w, x, y, z = quat_wxyz
    m = trimesh.transformations.quaternion_matrix([w, x, y, z])
    m[:3, 3] = pos
    return m


def _body_matrices(geo: SceneGeometry) -> dict[str, np.ndarray]:
    return {"world": np.eye(4), "tu": _matrix(geo.tu_pos, geo.tu_quat)}


def _part_mesh(part):  # -> trimesh.Trimesh
    import trimesh

    if part.kind == "box":
        return trimesh.creation.box(extents=[2 * s for s in part.size])
    if part.kind == "cylinder":
        return trimesh.creation.cylinder(radius=part.size[0], height=2 * part.size[1],
                                         sections=32)  # fmt: skip
    return trimesh.Trimesh(part.mesh.vertices, part.mesh.faces, process=False)


def _coloured(mesh, rgba: tuple[float, ...]):
    import trimesh

    colour = np.clip(np.round(np.asarray(rgba) * 255), 0, 255).astype(np.uint8)
    faces = np.tile(colour, (len(mesh.faces), 1))
    mesh.visual = trimesh.visual.ColorVisuals(mesh, face_colors=faces)
    return mesh


def _beam(geo: SceneGeometry, pos, quat, body: str):
    import trimesh

    beam = trimesh.creation.cylinder(radius=_BEAM_RADIUS_M, height=geo.beam_m, sections=8)
    beam.apply_translation([0.0, 0.0, geo.beam_m / 2])  # along the site's +z
    return _body_matrices(geo)[body] @ _matrix(pos, quat), beam


def _static_scene(replay: Replay, geo: SceneGeometry):  # -> trimesh.Scene
    import trimesh

    scene = trimesh.Scene()
    bodies = _body_matrices(geo)
    for part in geo.parts:
        if part.body == "object":
            continue
        mesh = _coloured(_part_mesh(part), part.rgba)
        scene.add_geometry(mesh, node_name=part.name, geom_name=part.name,
                           transform=bodies[part.body] @ _matrix(part.pos, part.quat))  # fmt: skip
    for name, body, pos, quat in geo.barriers:
        short = name.replace("_barrier_", "_")
        transform, beam = _beam(geo, pos, quat, body)
        scene.add_geometry(_coloured(beam, (0.37, 0.82, 0.48, 1.0)), node_name=f"{short}_beam",
                           geom_name=f"{short}_beam", transform=transform)  # fmt: skip
        transform, cut = _beam(geo, pos, quat, body)
        cut.apply_scale(1.6)  # a thicker red beam around the green one
        scene.add_geometry(_coloured(cut, (1.0, 0.23, 0.19, 1.0)), node_name=f"{short}_cut",
                           geom_name=f"{short}_cut", transform=transform)  # fmt: skip
    obj = trimesh.Trimesh(geo.object_mesh.vertices, geo.object_mesh.faces, process=False)
    scene.add_geometry(_coloured(obj, (0.69, 0.56, 0.38, 1.0)), node_name="object",
                       geom_name="object")  # fmt: skip
    return scene


def glb_bytes(replay: Replay, geometry: SceneGeometry | None = None) -> bytes:
    """The animated .glb of `replay` (see the module doc)."""
    import pygltflib as g

    geo = geometry if geometry is not None else replay_geometry(replay)
    data = _static_scene(replay, geo).export(file_type="glb")
    gltf = g.GLTF2.load_from_bytes(data)
    blob = bytearray(gltf.binary_blob() or b"")
    index = {node.name: i for i, node in enumerate(gltf.nodes)}

    def add(array: np.ndarray, kind: str, bounds: bool = False) -> int:
        raw = np.ascontiguousarray(array, dtype="<f4")
        while len(blob) % 4:
            blob.append(0)
        gltf.bufferViews.append(g.BufferView(buffer=0, byteOffset=len(blob),
                                             byteLength=raw.nbytes))  # fmt: skip
        blob.extend(raw.tobytes())
        acc = g.Accessor(bufferView=len(gltf.bufferViews) - 1, componentType=g.FLOAT,
                         count=len(raw), type=kind)  # fmt: skip
        if bounds:
            acc.min, acc.max = [float(raw.min())], [float(raw.max())]
        gltf.accessors.append(acc)
        return len(gltf.accessors) - 1

    times = add(replay.t_s - replay.t_s[0], g.SCALAR, bounds=True)
    samplers: list[g.AnimationSampler] = []
    channels: list[g.AnimationChannel] = []

    def animate(node: str, path: str, values: np.ndarray, kind: str, step: bool = False) -> None:
        samplers.append(g.AnimationSampler(input=times, output=add(values, kind),
                                           interpolation="STEP" if step else "LINEAR"))  # fmt: skip
        channels.append(g.AnimationChannel(sampler=len(samplers) - 1,
                                           target=g.AnimationChannelTarget(node=index[node],
                                                                           path=path)))  # fmt: skip

    _to_trs(gltf.nodes[index["object"]])
    animate("object", "translation", replay.qpos[:, :3], g.VEC3)
    quat = replay.qpos[:, [4, 5, 6, 3]]  # glTF: x, y, z, w, unit (a camera's are rounded)
    animate("object", "rotation", quat / np.linalg.norm(quat, axis=1, keepdims=True), g.VEC4)
    for k, name in enumerate(BARRIER_NAMES):
        node = f"{name}_cut"
        if node not in index:
            continue
        on = replay.barriers[:, k].astype(float)
        scale = np.repeat(np.maximum(on, 1e-4)[:, None], 3, axis=1)  # ~0: hidden
        animate(node, "scale", scale, g.VEC3, step=True)
        # The node keeps its matrix: split it into TRS so that the scale channel applies.
        _to_trs(gltf.nodes[index[node]])
    gltf.animations.append(g.Animation(name="replay", samplers=samplers, channels=channels))
    _z_up_root(gltf, g)
    gltf.buffers[0].byteLength = len(blob)
    gltf.set_binary_blob(bytes(blob))
    return b"".join(gltf.save_to_bytes())


def _to_trs(node) -> None:
    """Replace a node's matrix by translation, rotation and scale (animation needs TRS)."""
    import trimesh

    if node.matrix is None:
        return
    m = np.array(node.matrix, dtype=float).reshape(4, 4).T  # glTF: column-major
    w, x, y, z = trimesh.transformations.quaternion_from_matrix(m)
    node.translation = [float(v) for v in m[:3, 3]]
    node.rotation = [float(x), float(y), float(z), float(w)]
    node.scale = [1.0, 1.0, 1.0]
    node.matrix = None


def _z_up_root(gltf, g) -> None:
    """Parent the scene's roots to one node that turns z-up (F_T) into glTF's y-up."""
    scene = gltf.scenes[gltf.scene or 0]
    half = math.sqrt(0.5)
    gltf.nodes.append(g.Node(name="F_T (z up)", rotation=[-half, 0.0, 0.0, half],
                             children=list(scene.nodes)))  # fmt: skip
    scene.nodes = [len(gltf.nodes) - 1]


def write_glb(replay: Replay, path: str | Path) -> Path:
    """Write `replay` as an animated .glb (atomically)."""
    return write_atomic(path, glb_bytes(replay))
