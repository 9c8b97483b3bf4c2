"""Replays of experiments: re-simulate one E^V deterministically, or take a plant experiment
E^P's recording (a camera's, the barriers', the log's), and show it in 3-D (the console's
three.js view), or export it (glTF with animation, GIF, MP4).
"""

from transfertwin.replay._gif import (
    MAX_GIF_FRAMES,
    caption_text,
    gif_frame_times,
    outcome_words,
    render_frames,
    travel_of,
    write_gif,
)
from transfertwin.replay._gltf import glb_bytes, write_glb
from transfertwin.replay._mp4 import write_mp4
from transfertwin.replay._payload import (
    PAYLOAD_VERSION,
    belt_travel,
    replay_geometry,
    replay_payload,
)
from transfertwin.replay._plant import PlantRow, plant_row, plant_source, record_plant
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
    study_spec,
    transfer_spec,
)
from transfertwin.replay._words import outcome_text, state_text, status_text

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
    "PlantRow",
    "Replay",
    "SceneGeometry",
    "StudyRow",
    "belt_travel",
    "calibration_source",
    "calibration_spec",
    "caption_text",
    "compare_with_row",
    "compile_system",
    "gif_frame_times",
    "glb_bytes",
    "outcome_text",
    "outcome_words",
    "plant_row",
    "plant_source",
    "record_experiment",
    "record_plant",
    "render_frames",
    "replay_geometry",
    "replay_payload",
    "scene_geometry",
    "state_text",
    "status_text",
    "study_spec",
    "transfer_spec",
    "travel_of",
    "write_gif",
    "write_glb",
    "write_mp4",
]
