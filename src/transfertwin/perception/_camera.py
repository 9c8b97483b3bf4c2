"""The virtual RGB-D camera on the TM's servo: depth rendered from the MuJoCo scene.

`DepthCamera` renders a compiled MuJoCo scene (a `VirtualTransferSystem`'s model and data,
or the two-object scene of `pair_scene`) with `mujoco.Renderer`'s depth
mode from the camera pose T_TC(α) (Table 5.1, `camera_pose`), applies the noise model
(`DepthNoise`) and back-projects the pixels through a pinhole model into a point cloud in
F_C. Only the geoms are drawn: sites and MuJoCo's rangefinder rays are switched off, so
the light barriers do not show in the depth image. Rendering works headless (EGL/OSMesa).

The image's horizontal axis is x_C (along the direction of travel at α = 0), its rows run
along y_C = −y_T. `fovy_deg` is the field of view across the rows (default 65°, the
Kinect's narrow depth mode); the horizontal field follows from the aspect ratio.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import mujoco
import numpy as np

from transfertwin._errors import InputError
from transfertwin.perception._frames import ServoRig, camera_pose
from transfertwin.perception._noise import DepthNoise, apply_depth_noise

__all__ = ["CameraIntrinsics", "DepthCamera", "View", "depth_to_points"]


@dataclass(frozen=True)
class CameraIntrinsics:
    """Pinhole intrinsics of the depth image.

    Attributes:
        width, height: Image size in pixels.
        fovy_deg: Vertical field of view (degrees).
    """

    width: int = 320
    height: int = 240
    fovy_deg: float = 65.0

    def __post_init__(self) -> None:
        if not (8 <= self.width <= 1920 and 8 <= self.height <= 1080):
            raise InputError("CameraIntrinsics: size must be within 8x8 and 1920x1080 pixels")
        if not 1.0 <= self.fovy_deg <= 150.0:
            raise InputError("CameraIntrinsics: fovy_deg must lie in [1, 150]")

    @property
    def focal_px(self) -> float:
        """Focal length in pixels (square pixels)."""
        return 0.5 * self.height / math.tan(math.radians(self.fovy_deg) / 2.0)


@dataclass(frozen=True)
class View:
    """One captured frame: the cloud in F_C and where the camera was.

    Attributes:
        points_c: (H·W, 3) points in F_C (m), row-major over the image; NaN rows are
            pixels without depth.
        t_tc: (4, 4) camera pose in F_T when the frame was taken.
        alpha_rad: The servo angle.
    """

    points_c: np.ndarray
    t_tc: np.ndarray
    alpha_rad: float

    def points_t(self) -> np.ndarray:
        """The valid points (n, 3) in F_T."""
        valid = np.isfinite(self.points_c).all(axis=1)
        pts = self.points_c[valid]
        return pts @ self.t_tc[:3, :3].T + self.t_tc[:3, 3]


def depth_to_points(depth_m: np.ndarray, intrinsics: CameraIntrinsics) -> np.ndarray:
    """Back-project a depth image (H, W) (m along the optical axis) into F_C, (H·W, 3).

    Pixel (row v, column u) has its centre at (u + 0.5, v + 0.5); NaN depth stays NaN.
    """
    h, w = depth_m.shape
    f = intrinsics.focal_px
    u = (np.arange(w) + 0.5 - 0.5 * w) / f
    v = (np.arange(h) + 0.5 - 0.5 * h) / f
    z = np.asarray(depth_m, dtype=np.float64)
    x = z * u[None, :]
    y = z * v[:, None]
    return np.stack([x, y, z], axis=-1).reshape(-1, 3)


class DepthCamera:
    """A depth camera on the servo of the TM.

    Args:
        model, data: The scene rendered (not modified), e.g. a `VirtualTransferSystem`'s
            `model` and `data`; world = F_T.
        rig: Servo and camera mounting.
        intrinsics: Image size and field of view.
        noise: Noise and dropout model.

    Use as a context manager (or call `close`) to free the OpenGL context.
    """

    def __init__(
        self,
        model: mujoco.MjModel,
        data: mujoco.MjData,
        rig: ServoRig | None = None,
        intrinsics: CameraIntrinsics | None = None,
        noise: DepthNoise | None = None,
    ) -> None:
        self.data = data
        self.rig = rig if rig is not None else ServoRig()
        self.intrinsics = intrinsics if intrinsics is not None else CameraIntrinsics()
        self.noise = noise if noise is not None else DepthNoise()
        self._renderer = mujoco.Renderer(model, self.intrinsics.height, self.intrinsics.width)
        self._renderer.enable_depth_rendering()
        self._option = mujoco.MjvOption()
        self._option.flags[mujoco.mjtVisFlag.mjVIS_RANGEFINDER] = False
        self._option.sitegroup[:] = 0

    def __enter__(self) -> DepthCamera:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def close(self) -> None:
        """Free the renderer's OpenGL context."""
        self._renderer.close()

    def render_depth(self, alpha_rad: float) -> np.ndarray:
        """Noise-free depth (H, W) along the optical axis (m) at servo angle α."""
        t_tc = camera_pose(self.rig, alpha_rad)
        renderer = self._renderer
        renderer.update_scene(self.data, scene_option=self._option)
        top = math.tan(math.radians(self.intrinsics.fovy_deg) / 2.0)
        for cam in renderer.scene.camera:
            cam.pos[:] = t_tc[:3, 3]
            cam.forward[:] = t_tc[:3, 2]  # z_C: the optical axis
            cam.up[:] = -t_tc[:3, 1]  # image up is −y_C
            cam.orthographic = 0
            cam.frustum_center = 0.0
            cam.frustum_width = 0.0  # from the aspect ratio
            cam.frustum_top = cam.frustum_near * top
            cam.frustum_bottom = -cam.frustum_near * top
        return renderer.render().astype(np.float64)

    def capture(self, alpha_rad: float, seed: int) -> View:
        """One noisy frame at servo angle α (rad), its draws seeded by `seed`."""
        depth = apply_depth_noise(self.render_depth(alpha_rad), self.noise, seed)
        return View(depth_to_points(depth, self.intrinsics), camera_pose(self.rig, alpha_rad),
                    float(alpha_rad))  # fmt: skip
