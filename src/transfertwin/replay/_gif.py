"""A replay as a short animated GIF for reports: MuJoCo's offscreen renderer, Pillow.
(`render_frames` makes the frames; `transfertwin.replay._mp4` writes the same as MP4.)

Frames are rendered in a freshly compiled system with the TU docked as in the replay, from
the strip camera of `transfertwin.sim.strip_camera`, at `fps` frames per second of the GIF
and `speed` simulated seconds per second; each frame shows the sample at or before its time
and a caption: the time, the OTS state and the light barriers.
"""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path

import mujoco
import numpy as np
from PIL import Image, ImageDraw, ImageFont

from transfertwin._errors import InputError
from transfertwin.replay._record import BARRIER_NAMES, OTS_CODES, Replay, compile_system
from transfertwin.sim import strip_camera

__all__ = ["MAX_GIF_FRAMES", "gif_frame_times", "render_frames", "write_gif"]

#: At most this many frames (a longer replay plays faster than asked).
MAX_GIF_FRAMES = 600
_NAMES = {code: name.replace("_", "-") for name, code in OTS_CODES.items()}


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
    font = _font()
    with mujoco.Renderer(system.model, height, width) as renderer:
        cam = strip_camera(system)
        for t in times:
            i = max(0, int(np.searchsorted(replay.t_s, t + 1e-9, side="right")) - 1)
            qpos = np.array(replay.qpos[i], dtype=float)
            qpos[3:] /= np.linalg.norm(qpos[3:])  # a camera's quaternion is rounded
            system.set_object_qpos(qpos)
            renderer.update_scene(system.data, camera=cam, scene_option=option)
            image = Image.fromarray(renderer.render())
            _caption(image, replay, i, float(t), font)
            yield image


def _font() -> ImageFont.ImageFont | ImageFont.FreeTypeFont:
    try:
        import matplotlib

        ttf = Path(matplotlib.get_data_path()) / "fonts" / "ttf" / "DejaVuSans.ttf"
        return ImageFont.truetype(str(ttf), 15)
    except (ImportError, OSError):
        return ImageFont.load_default(size=15)


def _caption(image: Image.Image, replay: Replay, i: int, t: float, font) -> None:
    draw = ImageDraw.Draw(image)
    cut = [n.replace("_", " ") for n, on in zip(BARRIER_NAMES, replay.barriers[i], strict=True)
           if on]  # fmt: skip
    text = (f"t = {t:5.2f} s   OTS: {_NAMES.get(int(replay.ots[i]), '?')}   "
            f"barriers cut: {', '.join(cut) or 'none'}")  # fmt: skip
    draw.rectangle((0, 0, image.width, 24), fill=(20, 22, 28))
    draw.text((8, 4), text, fill=(235, 235, 235), font=font)
