"""Offscreen rendering of a transfer as a strip of frames (like the study's Fig. 6.8).

Rendering replays recorded object poses in the compiled system, so it costs nothing while
the experiment runs. Works headless on the CPU (EGL or OSMesa, see `MUJOCO_GL`).
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import mujoco
import numpy as np
from PIL import Image, ImageDraw

from transfertwin.sim._system import VirtualTransferSystem

__all__ = ["pick_frames", "render_strip"]


def pick_frames(n_available: int, n_wanted: int) -> list[int]:
    """Indices of `n_wanted` frames spread evenly from the first to the last one."""
    if n_available <= 0:
        return []
    n = min(n_wanted, n_available)
    if n == 1:
        return [n_available - 1]
    return sorted({round(i * (n_available - 1) / (n - 1)) for i in range(n)})


def _camera() -> mujoco.MjvCamera:
    cam = mujoco.MjvCamera()
    cam.type = mujoco.mjtCamera.mjCAMERA_FREE
    cam.lookat[:] = (0.0, 0.0, 0.02)
    cam.distance = 0.95
    cam.azimuth = 200.0
    cam.elevation = -55.0
    return cam


def render_strip(
    system: VirtualTransferSystem,
    poses: Sequence[tuple[str, float, Sequence[float]]],
    path: str | Path,
    *,
    n_frames: int = 8,
    width: int = 320,
    height: int = 240,
    title: str = "",
) -> Path:
    """Render recorded poses into one PNG strip (frames left to right, t_0 to t_end).

    Args:
        system: The system the poses were recorded in (TU still docked as then).
        poses: (label, time in s, object qpos (7,)) per recorded sample.
        path: Output PNG path.
        n_frames: Number of frames in the strip.
        width, height: Size of one frame in pixels.
        title: Text drawn above the strip.

    Returns:
        The written path.
    """
    path = Path(path)
    picked = [poses[i] for i in pick_frames(len(poses), n_frames)]
    header = 22 if title else 0
    strip = Image.new("RGB", (width * max(1, len(picked)), height + header), "white")
    draw = ImageDraw.Draw(strip)
    if title:
        draw.text((6, 4), title, fill=(0, 0, 0))
    with mujoco.Renderer(system.model, height, width) as renderer:
        cam = _camera()
        for k, (label, t_s, qpos) in enumerate(picked):
            system.set_object_qpos(np.asarray(qpos, dtype=float))
            renderer.update_scene(system.data, camera=cam)
            frame = Image.fromarray(renderer.render())
            ImageDraw.Draw(frame).text((6, 6), f"{label} t={t_s:.2f}s", fill=(255, 255, 255))
            strip.paste(frame, (k * width, header))
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(path.name + ".tmp")
    strip.save(tmp, format="PNG")
    tmp.replace(path)
    return path
