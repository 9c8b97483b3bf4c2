"""A replay as a short MP4 clip for reports and slides: the GIF's frames, encoded as H.264.

The frames are `render_frames`' (the GIF's: MuJoCo's offscreen renderer, the strip camera,
the caption) at the same times (`gif_frame_times`: `fps` frames per second, `speed`
simulated seconds per second). They are piped into the ffmpeg binary that the
``imageio-ffmpeg`` wheel ships (no system ffmpeg needed) and encoded with libx264, yuv420p
(what browsers, PowerPoint and every player take), in one thread and with bit-exact muxing,
so the same replay gives the same file, byte for byte. Written whole, then renamed.
"""

from __future__ import annotations

import contextlib
from pathlib import Path

from transfertwin.replay._gif import gif_frame_times, render_frames
from transfertwin.replay._record import Replay

__all__ = ["write_mp4"]


def write_mp4(
    replay: Replay, path: str | Path, *, fps: int = 10, speed: float = 2.0,
    width: int = 640, height: int = 360,
) -> Path:  # fmt: skip
    """Render `replay` into an H.264 MP4 at `path` (see the module doc)."""
    import imageio_ffmpeg

    if width % 2 or height % 2:
        raise ValueError(f"an MP4 frame needs even sides, got {width}x{height}")
    path = Path(path)
    times = gif_frame_times(replay.duration_s, fps, speed)
    tmp = path.with_name(path.name + ".tmp")
    writer = imageio_ffmpeg.write_frames(
        str(tmp), (width, height), fps=fps, codec="libx264", pix_fmt_out="yuv420p",
        quality=None, bitrate=None, macro_block_size=2, ffmpeg_log_level="error",
        output_params=["-crf", "23", "-preset", "medium", "-threads", "1",
                       "-fflags", "+bitexact", "-flags:v", "+bitexact", "-map_metadata", "-1",
                       "-movflags", "+faststart", "-f", "mp4"],
    )  # fmt: skip
    try:
        writer.send(None)  # start ffmpeg
        for image in render_frames(replay, times, width=width, height=height):
            writer.send(image.convert("RGB").tobytes())
        writer.close()
    except BaseException:
        writer.close()
        with contextlib.suppress(OSError):
            tmp.unlink()
        raise
    tmp.replace(path)
    return path
