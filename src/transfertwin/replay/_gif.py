"""A replay as a short animated GIF for reports: MuJoCo's offscreen renderer, Pillow.
(`render_frames` makes the frames; `transfertwin.replay._mp4` writes the same as MP4.)

Frames are rendered in a freshly compiled system with the TU docked as in the replay, from
the strip camera of `transfertwin.sim.strip_camera`, at `fps` frames per second of the GIF
and `speed` simulated seconds per second; each frame shows the sample at or before its time,
the strip's marks (`transfertwin.sim.annotate_frame`: TM and TU, L/R, the light barriers and
an arrow for the direction the belts run) and a caption in words (`caption_text`): the time,
what is happening ('crossing TM → TU', 'delivered'), the barriers cut, and from the last
transfer's end on the experiment's outcome.
"""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path

import mujoco
import numpy as np
from PIL import Image

from transfertwin._errors import InputError
from transfertwin.replay._record import BARRIER_NAMES, OTS_CODES, Replay, compile_system
from transfertwin.replay._words import outcome_text
from transfertwin.sim import annotate_frame, strip_camera

__all__ = [
    "MAX_GIF_FRAMES",
    "caption_text",
    "gif_frame_times",
    "outcome_words",
    "render_frames",
    "travel_of",
    "write_gif",
]

#: At most this many frames (a longer replay plays faster than asked).
MAX_GIF_FRAMES = 600
_CODES = {code: name for name, code in OTS_CODES.items()}
_WAY = {1: "TM → TU", -1: "TU → TM"}


def gif_frame_times(duration_s: float, fps: int, speed: float) -> np.ndarray:
    """Simulated times of the GIF's frames: every speed/fps s from 0, the end included."""
    if fps < 1 or fps > 50:
        raise InputError(f"--fps must be in 1..50, got {fps}")
    if not 0.1 <= speed <= 100:
        raise InputError(f"--speed must be in 0.1..100, got {speed}")
    step = max(speed / fps, duration_s / (MAX_GIF_FRAMES - 1))
    times = np.arange(0.0, duration_s, step)
    return np.append(times, duration_s)


def write_gif(
    replay: Replay, path: str | Path, *, fps: int = 10, speed: float = 2.0,
    width: int = 640, height: int = 360,
) -> Path:  # fmt: skip
    """Render `replay` into an animated GIF at `path` (written whole, then renamed)."""
    path = Path(path)
    times = gif_frame_times(replay.duration_s, fps, speed)
    frames = [image.convert("P", palette=Image.Palette.ADAPTIVE, colors=128)
              for image in render_frames(replay, times, width=width, height=height)]  # fmt: skip
    tmp = path.with_name(path.name + ".tmp")
    frames[0].save(tmp, format="GIF", save_all=True, append_images=frames[1:],
                   duration=round(1000 / fps), loop=0)  # fmt: skip
    tmp.replace(path)
    return path


def render_frames(
    replay: Replay, times: np.ndarray, *, width: int = 640, height: int = 360
) -> Iterator[Image.Image]:
    """RGB frames of `replay` at simulated `times`, one by one (see the module doc): the
    sample at or before each time, from the strip camera, with the caption."""
    system = compile_system(replay.spec)
    system.reset(replay.spec.docking_error)
    option = mujoco.MjvOption()
    option.flags[mujoco.mjtVisFlag.mjVIS_RANGEFINDER] = True
    with mujoco.Renderer(system.model, height, width) as renderer:
        cam = strip_camera(system)
        for t in times:
            i = max(0, int(np.searchsorted(replay.t_s, t + 1e-9, side="right")) - 1)
            qpos = np.array(replay.qpos[i], dtype=float)
            qpos[3:] /= np.linalg.norm(qpos[3:])  # a camera's quaternion is rounded
            system.set_object_qpos(qpos)
            renderer.update_scene(system.data, camera=cam, scene_option=option)
            image = Image.fromarray(renderer.render())
            annotate_frame(image, renderer.scene, system, caption_text(replay, i, float(t)),
                           travel_of(replay, i))  # fmt: skip
            yield image


def travel_of(replay: Replay, i: int) -> int:
    """The direction the belts run at sample `i`: +1 TM → TU, -1 TU → TM, 0 stopped."""
    total = float(np.sum(replay.belts[i]))
    return 0 if abs(total) < 1e-9 else (1 if total > 0 else -1)


def _last_travel(replay: Replay, i: int) -> int:
    """The direction of the latest sample up to `i` in which the belts ran (0: none yet)."""
    for k in range(i, -1, -1):
        if way := travel_of(replay, k):
            return way
    return 0


def outcome_words(replay: Replay) -> str:
    """The experiment's outcome in words: a virtual one's (`outcome_text`), a plant
    experiment's as its log gives it."""
    if replay.result is not None:
        return outcome_text(replay.result.row())
    row = replay.logged or {}
    return "delivered (the plant's log)" if row.get("success") == 1 else "failed (the plant's log)"


def _doing(replay: Replay, i: int) -> str:
    kind = _CODES.get(int(replay.ots[i]), "none")
    way = _WAY.get(_last_travel(replay, i), "")
    back = way == "TU → TM"
    words = {
        "none": "belts stopped" if way else "object placed, settling",
        "pre": f"start state: the transfer {way} begins",
        "non_terminal": f"crossing {way}".strip(),
        "success": "brought back to the TM" if back else "delivered to the TU",
        "failure": f"failed {way}".strip(),
        "invalid": "not a start state: no transfer",
    }
    return words[kind]


def caption_text(replay: Replay, i: int, t_s: float) -> str:
    """A frame's caption in words: the time, what is happening at sample `i` and the
    barriers cut; from the last marker on (the experiment has ended), its outcome."""
    ended = bool(replay.markers) and t_s >= replay.markers[-1].t_s - 1e-9 and i > 0
    cut = [n.replace("_", " ") for n, on in zip(BARRIER_NAMES, replay.barriers[i], strict=True)
           if on]  # fmt: skip
    what = outcome_words(replay) if ended else _doing(replay, i)
    return f"t = {t_s:5.2f} s · {what} · barriers cut: {', '.join(cut) or 'none'}"
