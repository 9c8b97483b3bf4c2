"""Replays of virtual experiments: re-simulate one E^V deterministically, record it, and show
it in 3-D (the console's three.js view), or export it (glTF with animation, GIF).
"""

from transfertwin.replay._gif import MAX_GIF_FRAMES, gif_frame_times, write_gif
from transfertwin.replay._gltf import glb_bytes, write_glb
from transfertwin.replay._payload import (
    PAYLOAD_VERSION,
    belt_travel,
    replay_geometry,
    replay_payload,
)
from transfertwin.replay._record import (
    BARRIER_NAMES,
    BELT_NAMES,
    OTS_CODES,
    Marker,
    Replay,
    compile_system,
    record_experiment,
)
from transfertwin.replay._scene import GeomPart, MeshData, SceneGeometry, scene_geometry
from transfertwin.replay._source import (
    BUILTIN_REAL,
    COMPARED_COLUMNS,
    CalibrationRow,
    StudyRow,
    calibration_source,
    calibration_spec,
    compare_with_row,
    parse_dock_error,
    study_spec,
    transfer_spec,
)

__all__ = [
    "BARRIER_NAMES",
    "BELT_NAMES",
    "BUILTIN_REAL",
    "COMPARED_COLUMNS",
    "MAX_GIF_FRAMES",
    "OTS_CODES",
    "PAYLOAD_VERSION",
    "CalibrationRow",
    "GeomPart",
    "Marker",
    "MeshData",
    "Replay",
    "SceneGeometry",
    "StudyRow",
    "belt_travel",
    "calibration_source",
    "calibration_spec",
    "compare_with_row",
    "compile_system",
    "gif_frame_times",
    "glb_bytes",
    "parse_dock_error",
    "record_experiment",
    "replay_geometry",
    "replay_payload",
    "scene_geometry",
    "study_spec",
    "transfer_spec",
    "write_gif",
    "write_glb",
]
