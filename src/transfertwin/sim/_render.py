"""Offscreen rendering of a transfer as a strip of frames (like the study's Fig. 6.8).

Rendering replays recorded object poses in the compiled system, so it costs nothing while
the experiment runs. Works headless on the CPU (EGL or OSMesa, see `MUJOCO_GL`).

The view follows the study's convention: the camera looks across the belts from the right
(-y) side and down, so the direction of travel TM → TU (+x of F_T) runs left to right in
the image and the *left* belt (y > 0, on the left looking in the direction of travel) is the
far one, at the top of each frame. Every frame is annotated: TM and TU, L/R on the belts,
the light barriers (yellow when interrupted, grey when clear; MuJoCo's own rangefinder rays
are switched off so that only these marks show them) and an arrow for the direction the
belts run in that phase. One row per phase (e.g. the transfer there, then the way back),
a header with the caller's text and a legend at the bottom.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from pathlib import Path

import mujoco
import numpy as np
from PIL import Image, ImageDraw, ImageFont

from transfertwin.sim._scene import BARRIERS, UNITS
from transfertwin.sim._system import VirtualTransferSystem

__all__ = [
    "annotate_frame",
    "group_frames",
    "pick_frames",
    "project_points",
    "render_strip",
    "strip_camera",
    "strip_pixels",
]

_YELLOW = (250, 200, 0)
_GREY = (170, 170, 170)
_WHITE = (255, 255, 255)
_BLACK = (0, 0, 0)
_LABEL_BG = (30, 30, 30)


def pick_frames(n_available: int, n_wanted: int) -> list[int]:
    """Indices of `n_wanted` frames spread evenly from the first to the last one."""
    if n_available <= 0:
        return []
    n = min(n_wanted, n_available)
    if n == 1:
        return [n_available - 1]
    return sorted({round(i * (n_available - 1) / (n - 1)) for i in range(n)})


def group_frames(labels: Sequence[str], per_group: int) -> list[list[int]]:
    """Indices of up to `per_group` evenly spread frames per run of equal labels, in order.

    The first and the last frame of each run are always kept, so a row of the strip starts
    at the start of its phase and ends at its end.
    """
    groups: list[list[int]] = []
    start = 0
    for i in range(1, len(labels) + 1):
        if i == len(labels) or labels[i] != labels[start]:
            groups.append([start + j for j in pick_frames(i - start, per_group)])
            start = i
    return groups


def strip_camera(system: VirtualTransferSystem) -> mujoco.MjvCamera:
    """The free camera of the strip: from the right side and above, travel left to right."""
    layout = system.cfg.layout
    x0 = -layout.tm_length_m
    x1 = system.tu_pose[0] + layout.tu_length_m
    cam = mujoco.MjvCamera()
    cam.type = mujoco.mjtCamera.mjCAMERA_FREE
    cam.lookat[:] = (0.5 * (x0 + x1), 0.0, 0.0)
    cam.distance = 0.66 * (x1 - x0) + 0.12
    cam.azimuth = 90.0  # looking along +y: image right = +x (the direction of travel)
    cam.elevation = -62.0
    return cam


def project_points(scene: mujoco.MjvScene, points: np.ndarray, width: int, height: int):
    """Pixel coordinates (u, v) of world points (n, 3) in a rendered scene's camera."""
    cam = mujoco.mjv_averageCamera(scene.camera[0], scene.camera[1])  # the two stereo eyes
    pos, fwd, up = np.array(cam.pos), np.array(cam.forward), np.array(cam.up)
    right = np.cross(fwd, up)
    rel = np.atleast_2d(points) - pos
    x, y, z = rel @ right, rel @ up, rel @ fwd
    if cam.orthographic:
        xn, yn = x, y
    else:
        xn, yn = x * cam.frustum_near / z, y * cam.frustum_near / z
    # A zero frustum width means "from the viewport's aspect ratio" (as mjr_render does).
    half_w = cam.frustum_width or 0.5 * (cam.frustum_top - cam.frustum_bottom) * width / height
    u = (xn - (cam.frustum_center - half_w)) / (2.0 * half_w) * width
    v = (cam.frustum_top - yn) / (cam.frustum_top - cam.frustum_bottom) * height
    return np.stack([u, v], axis=1)


def strip_pixels(
    system: VirtualTransferSystem, points: np.ndarray, width: int = 480, height: int = 260
) -> np.ndarray:
    """Where world points (n, 3) land in a strip frame of this size, pixels (n, 2) (u, v).

    Needs no OpenGL context: the abstract scene alone fixes the camera.
    """
    scene = mujoco.MjvScene(system.model, maxgeom=1000)
    mujoco.mjv_updateScene(
        system.model, system.data, mujoco.MjvOption(), None, strip_camera(system),
        int(mujoco.mjtCatBit.mjCAT_ALL), scene,
    )  # fmt: skip
    return project_points(scene, np.asarray(points, dtype=float), width, height)


def _font(size: int) -> ImageFont.ImageFont | ImageFont.FreeTypeFont:
    """DejaVu Sans (has θ, arrows) from matplotlib's data if present, else Pillow's default."""
    try:
        import matplotlib

        path = Path(matplotlib.get_data_path()) / "fonts" / "ttf" / "DejaVuSans.ttf"
        return ImageFont.truetype(str(path), size)
    except (ImportError, OSError):
        return ImageFont.load_default(size=size)


def _unit_to_world(system: VirtualTransferSystem, unit: str, pts: np.ndarray) -> np.ndarray:
    """Points given in a unit's frame (TM: F_T itself; TU: its docked pose) in F_T."""
    if unit == "tm":
        return pts
    x, y, yaw = system.tu_pose
    c, s = math.cos(yaw), math.sin(yaw)
    out = pts.copy()
    out[:, 0] = x + c * pts[:, 0] - s * pts[:, 1]
    out[:, 1] = y + s * pts[:, 0] + c * pts[:, 1]
    return out


def _barrier_x(system: VirtualTransferSystem, unit: str, which: str) -> float:
    layout = system.cfg.layout
    if unit == "tm":
        near, far = -layout.barrier_inset_m, -layout.tm_length_m + layout.barrier_inset_m
    else:
        near, far = layout.barrier_inset_m, layout.tu_length_m - layout.barrier_inset_m
    return near if which == "near" else far


def _boxed_text(draw, xy, text, font, fg=_WHITE, bg=_LABEL_BG, anchor="la") -> None:
    box = draw.textbbox(xy, text, font=font, anchor=anchor)
    draw.rectangle((box[0] - 3, box[1] - 2, box[2] + 3, box[3] + 2), fill=bg)
    draw.text(xy, text, fill=fg, font=font, anchor=anchor)


def _arrow(draw, start, end, color, width: int = 4) -> None:
    (x0, y0), (x1, y1) = start, end
    draw.line((x0, y0, x1, y1), fill=color, width=width)
    ang = math.atan2(y1 - y0, x1 - x0)
    head = 12
    left = (x1 - head * math.cos(ang - 0.45), y1 - head * math.sin(ang - 0.45))
    right = (x1 - head * math.cos(ang + 0.45), y1 - head * math.sin(ang + 0.45))
    draw.polygon([(x1, y1), left, right], fill=color)


def _annotate(
    frame: Image.Image,
    scene: mujoco.MjvScene,
    system: VirtualTransferSystem,
    label: str,
    travel: int,
    fonts: tuple,
) -> None:
    """Draw TM/TU, L/R, the light barriers and the travel arrow onto one frame."""
    small, big = fonts
    w, h = frame.size
    draw = ImageDraw.Draw(frame)
    layout = system.cfg.layout
    y_belt = layout.belt_separation_m / 2 + layout.belt_width_m / 2
    y_edge = layout.belt_separation_m / 2 + layout.belt_width_m + 0.01
    z_beam = layout.barrier_height_m

    def px(unit: str, pts: list[tuple[float, float, float]]) -> np.ndarray:
        world = _unit_to_world(system, unit, np.array(pts, dtype=float))
        return project_points(scene, world, w, h)

    # Light barriers: a line along each beam, yellow when interrupted.
    for unit in UNITS:
        hal = system.tm if unit == "tm" else system.tu
        state = hal.barriers()
        for which in BARRIERS:
            x = _barrier_x(system, unit, which)
            (u0, v0), (u1, v1) = px(unit, [(x, y_edge, z_beam), (x, -y_edge, z_beam)])
            color = _YELLOW if state[which] else _GREY
            draw.line((u0, v0, u1, v1), fill=color, width=4 if state[which] else 2)
    # Units: TM and TU beside their near (right) belt edge, where no object hides them.
    centres = {"tm": -0.5 * layout.tm_length_m, "tu": 0.5 * layout.tu_length_m}
    for unit, xc in centres.items():
        (u, v) = px(unit, [(xc, -y_edge - 0.02, 0.0)])[0]
        _boxed_text(draw, (u, v), unit.upper(), big, anchor="ma")
    # L and R on the TM belts near their upstream end (objects start mid-belt).
    x_mark = -layout.tm_length_m + 0.04
    for side, y in (("L", y_belt), ("R", -y_belt)):
        (u, v) = px("tm", [(x_mark, y, 0.0)])[0]
        _boxed_text(draw, (u, v), side, big, bg=(40, 70, 140), anchor="lm")
    # Travel direction of the belts in this phase.
    if travel:
        y_arrow = h - 18
        xa, xb = (0.36 * w, 0.64 * w) if travel > 0 else (0.64 * w, 0.36 * w)
        _arrow(draw, (xa, y_arrow), (xb, y_arrow), (230, 60, 40))
        text = "travel TM → TU" if travel > 0 else "travel TU → TM"
        _boxed_text(draw, (0.5 * w, y_arrow - 10), text, small, anchor="md")
    _boxed_text(draw, (6, 6), label, big)


def annotate_frame(
    frame: Image.Image,
    scene: mujoco.MjvScene,
    system: VirtualTransferSystem,
    label: str,
    travel: int,
    sizes: tuple[int, int] = (13, 16),
) -> None:
    """Draw the strip's marks onto one frame rendered from `strip_camera`: TM and TU, L/R
    on the belts, the light barriers, the travel arrow (`travel` +1: TM → TU, -1: TU → TM,
    0: none) and `label` at the top left.

    Args:
        frame: The rendered image, drawn on in place.
        scene: The renderer's scene after `update_scene` (its camera projects the marks).
        system: The system the frame shows (TU docked as then).
        label: Text at the top left.
        travel: Direction the belts run.
        sizes: Font sizes of the small and the big text (px).
    """
    _annotate(frame, scene, system, label, travel, (_font(sizes[0]), _font(sizes[1])))


_LEGEND = (
    ("line", _YELLOW, "light barrier, interrupted"),
    ("line", _GREY, "light barrier, clear"),
    ("arrow", (230, 60, 40), "direction the belts run"),
    ("box", (40, 70, 140), "L / R: left / right belt, seen looking from TM to TU"),
    ("box", _LABEL_BG, "TM transport module, TU transfer unit"),
)


def _draw_legend(draw: ImageDraw.ImageDraw, top: int, font) -> None:
    x = 10
    for kind, color, text in _LEGEND:
        y = top + 14
        if kind == "line":
            draw.line((x, y, x + 30, y), fill=color, width=4)
        elif kind == "arrow":
            _arrow(draw, (x, y), (x + 30, y), color, width=3)
        else:
            draw.rectangle((x + 6, y - 8, x + 24, y + 8), fill=color)
        draw.text((x + 38, y), text, fill=_BLACK, font=font, anchor="lm")
        x += 38 + int(draw.textlength(text, font=font)) + 28


def render_strip(
    system: VirtualTransferSystem,
    poses: Sequence[tuple[str, float, Sequence[float]]],
    path: str | Path,
    *,
    n_frames: int = 4,
    width: int = 480,
    height: int = 260,
    title: str | Sequence[str] = "",
    travel: Mapping[str, int] | None = None,
) -> Path:
    """Render recorded poses into one annotated PNG: a row of frames per phase.

    Args:
        system: The system the poses were recorded in (TU still docked as then).
        poses: (phase label, time in s, object qpos (7,)) per recorded sample, in order;
            consecutive samples with the same label form one row.
        path: Output PNG path.
        n_frames: Frames per row, evenly spread from the phase's first to its last sample.
        width, height: Size of one frame in pixels.
        title: Header text, one string per line.
        travel: Direction the belts run per phase label: +1 TM → TU, -1 TU → TM (an arrow
            in each frame); labels not in it get no arrow.

    Returns:
        The written path.
    """
    path = Path(path)
    lines = [title] if isinstance(title, str) else list(title)
    lines = [t for t in lines if t]
    travel = dict(travel or {})
    rows = group_frames([p[0] for p in poses], n_frames)
    n_cols = max((len(r) for r in rows), default=1)
    small, big, head = _font(13), _font(16), _font(17)
    header = 10 + 24 * len(lines)
    legend = 30
    strip = Image.new(
        "RGB", (width * n_cols, header + height * max(1, len(rows)) + legend), "white"
    )
    draw = ImageDraw.Draw(strip)
    for i, text in enumerate(lines):
        draw.text((8, 6 + 24 * i), text, fill=_BLACK, font=head)
    option = mujoco.MjvOption()
    option.flags[mujoco.mjtVisFlag.mjVIS_RANGEFINDER] = False
    with mujoco.Renderer(system.model, height, width) as renderer:
        cam = strip_camera(system)
        for r, row in enumerate(rows):
            for c, index in enumerate(row):
                label, t_s, qpos = poses[index]
                system.set_object_qpos(np.asarray(qpos, dtype=float))
                renderer.update_scene(system.data, camera=cam, scene_option=option)
                frame = Image.fromarray(renderer.render())
                end = " (end)" if c == len(row) - 1 and len(row) > 1 else ""
                _annotate(
                    frame, renderer.scene, system, f"{label}  t = {t_s:.2f} s{end}",
                    travel.get(label, 0), (small, big),
                )  # fmt: skip
                strip.paste(frame, (c * width, header + r * height))
    _draw_legend(draw, header + height * max(1, len(rows)), small)
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(path.name + ".tmp")
    strip.save(tmp, format="PNG")
    tmp.replace(path)
    return path
