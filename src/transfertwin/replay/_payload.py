"""A replay as one JSON document: the scene, the sampled motion and the OTS time line.

The console's 3-D view (`web/static/replay.js`) draws it; the same document is what
`transfertwin replay --json` writes. Meshes travel as base64 of little-endian float32
vertices and uint32 triangle indices (a tenth of the size of number lists); the motion as
lists rounded to 0.01 mm and 1e-6 of a quaternion (a plant experiment's as its camera saw it,
1 mm and 1e-3, and the belts' travel to 1 mm).
"""

from __future__ import annotations

import base64
import math
from typing import Any

import numpy as np

from transfertwin.replay._gif import outcome_words
from transfertwin.replay._record import (
    BARRIER_NAMES,
    BELT_NAMES,
    OTS_CODES,
    Replay,
    compile_system,
)
from transfertwin.replay._scene import MeshData, SceneGeometry, scene_geometry

__all__ = ["PAYLOAD_VERSION", "belt_travel", "replay_geometry", "replay_payload"]

#: Version of the document's layout (the page checks it).
PAYLOAD_VERSION = 1


def replay_geometry(replay: Replay) -> SceneGeometry:
    """The static scene of a replay (its spec's compiled system and object)."""
    spec = replay.spec
    system = compile_system(spec)
    return scene_geometry(system, spec.object_ref, spec.units, replay.tu_pose)


def belt_travel(replay: Replay) -> np.ndarray:
    """How far each belt's surface has moved by each sample (m), (n, 4): the speed noted
    after a wait is the one that drove it during that wait."""
    dt = np.diff(replay.t_s, prepend=replay.t_s[:1])
    return np.cumsum(replay.belts * dt[:, None], axis=0)


def _b64(array: np.ndarray, dtype: str) -> str:
    return base64.b64encode(np.ascontiguousarray(array, dtype=dtype).tobytes()).decode()


def _mesh(mesh: MeshData) -> dict[str, str]:
    return {"vertices": _b64(mesh.vertices, "<f4"), "faces": _b64(mesh.faces, "<u4")}


def _num(value: object) -> object:
    if isinstance(value, float) and math.isnan(value):
        return None
    if isinstance(value, np.generic):
        return value.item()
    return value


def _round(array: np.ndarray, digits: int) -> list[Any]:
    return np.round(np.asarray(array, dtype=float), digits).tolist()


def replay_payload(
    replay: Replay, geometry: SceneGeometry | None = None, *, title: str = "",
    source: dict[str, object] | None = None,
) -> dict[str, object]:
    """The JSON-able document of `replay` (see the module doc)."""
    geo = geometry if geometry is not None else replay_geometry(replay)
    spec, result = replay.spec, replay.result
    virtual = result is not None
    row = {k: _num(v) for k, v in (result.row() if virtual else replay.logged or {}).items()}
    bits = replay.barriers.astype(np.int64) @ (1 << np.arange(len(BARRIER_NAMES)))
    return {
        "version": PAYLOAD_VERSION,
        "title": title or (f"{row.get('object_id')}: {spec.face}, {spec.conveyor}, "
                           f"θ = {spec.theta_deg}°, run {spec.run}, seed {spec.seed}"),
        "source": source or {},
        "result": row,
        "outcome": outcome_words(replay),
        "spec": {"object": spec.object_ref, "face": spec.face, "conveyor": spec.conveyor,
                 "theta_deg": spec.theta_deg, "run": spec.run if virtual else None,
                 "seed": spec.seed if virtual else None,
                 "docking_error_mm_deg": list(spec.docking_error.as_mm_deg()) if virtual else
                 [row.get(c) for c in ("dock_err_x_mm", "dock_err_y_mm", "dock_err_theta_deg")],
                 "gap_m": spec.scene.gap_m, "t_max_s": spec.scene.t_max_s},
        "scene": {
            "parts": [
                {"name": p.name, "body": p.body, "kind": p.kind, "size": list(p.size),
                 "pos": list(p.pos), "quat": list(p.quat), "rgba": list(p.rgba),
                 **({"mesh": _mesh(p.mesh)} if p.mesh is not None else {})}
                for p in geo.parts
            ],
            "barriers": [{"name": n, "body": b, "pos": list(pos), "quat": list(q)}
                         for n, b, pos, q in geo.barriers],
            "beam_m": geo.beam_m,
            "tu": {"pos": list(geo.tu_pos), "quat": list(geo.tu_quat)},
            "nominal_tu": {"pos": list(geo.nominal_tu_pos), "quat": list(geo.nominal_tu_quat)},
            "tu_pose": list(replay.tu_pose),
            "floor_z": geo.floor_z,
            "object_mesh": _mesh(geo.object_mesh),
            "tm_length_m": geo.tm_length_m,
            "tu_length_m": geo.tu_length_m,
            "belt_half_span_m": geo.belt_half_span_m,
            "pulley_radius_m": spec.scene.layout.pulley_radius_m,
        },
        "frames": {
            "t": _round(replay.t_s, 6),
            "pos": _round(replay.qpos[:, :3], 5),
            "quat": _round(replay.qpos[:, 3:], 6),
            "barriers": bits.tolist(),
            "barrier_names": list(BARRIER_NAMES),
            "belts": _round(replay.belts, 4),
            "travel": _round(belt_travel(replay), 5 if virtual else 3),
            "belt_names": list(BELT_NAMES),
            "ots": replay.ots.tolist(),
        },
        "ots_codes": OTS_CODES,
        "markers": [
            {"t": round(m.t_s, 6), "kind": m.kind, "label": m.label} for m in replay.markers
        ],
    }
