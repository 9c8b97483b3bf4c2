"""Docking-error measurement with a ChArUco board (Sec. 6.1.2, Table 6.1, Eq. 6.11).

A 5×5 ChArUco board lies face up on the transport module; a fixed camera on the transfer unit
looks down at it. The camera image is rendered by a homography warp of the board image that
OpenCV generates (`CharucoBoard.generateImage`): a planar target seen by a distortion-free
pinhole camera maps to the image by exactly the homography K·[r₁ r₂ t], so the warp is the
exact rendering of this scene, needs no OpenGL context and takes milliseconds. (A MuJoCo scene
with the board as a texture would add only the renderer's own sampling.) The warp is drawn at
twice the camera resolution and averaged down (area interpolation) against aliasing.

The measurement follows the study: the board's pose is measured once at the goal
(the reference T_CT,BG, made after a manual docking in the study), then after each docking
(T_CT,B) with `CharucoDetector` and `solvePnP`, and the docking error is read from
T_DG,D = T_DG,BG · T_CT,BG⁻¹ · T_CT,B · T_D,B⁻¹ (Eq. 6.11), where T_D,B is the board's mounting
on the robot (so T_DG,BG = T_D,B).

Frames (3-D, metres): F_DG the goal docking frame (x towards the transfer unit, z up); F_D the
robot centre frame, its origin on the robot's top deck where the board lies (the study does not
fix its height; at deck height a small tilt error of the measured board does not leak into the
planar error through a vertical lever arm); F_B the board frame of OpenCV's board model; F_CT the
camera (z optical axis), 0.4 m above the deck and 0.25 m ahead of the board, looking at it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cached_property

import cv2
import numpy as np

__all__ = ["CharucoRig", "MeasuredPose", "planar_to_se3"]


def planar_to_se3(x: float, y: float, theta: float, z: float = 0.0) -> np.ndarray:
    """The 4×4 transform of a planar pose (x, y in m, yaw θ in rad) at height z."""
    c, s = math.cos(theta), math.sin(theta)
    t = np.eye(4)
    t[:2, :2] = [[c, -s], [s, c]]
    t[:3, 3] = [x, y, z]
    return t


def _look_at(eye: np.ndarray, target: np.ndarray) -> np.ndarray:
    """Camera pose (4×4, in the parent frame) at `eye` with its z axis through `target`."""
    z = (target - eye) / np.linalg.norm(target - eye)
    x = np.cross(z, [0.0, 0.0, 1.0])
    x /= np.linalg.norm(x)
    t = np.eye(4)
    t[:3, :3] = np.stack([x, np.cross(z, x), z], axis=1)
    t[:3, 3] = eye
    return t


@dataclass(frozen=True)
class MeasuredPose:
    """A board pose from one image: 4×4 T_CT,B (None: board not found) and corners used."""

    transform: np.ndarray | None
    corners: int


@dataclass(frozen=True)
class CharucoRig:
    """The board on the robot and the camera on the transfer unit.

    Attributes:
        squares: Squares per side (the study's board: 5×5).
        square_m, marker_m: Square and marker edge, m.
        board_xyz_m: Board centre in F_D (face up, on the deck), m.
        camera_xyz_m: Camera position in F_DG, m (it looks at the goal board centre).
        image_size: Camera resolution (width, height), px.
        focal_px: Focal length, px (principal point at the image centre, no distortion).
        pixel_noise_sd: 1σ Gaussian grey-level noise added to renders (0–255 scale).
        board_px: Side of the generated board image, px.
    """

    squares: int = 5
    square_m: float = 0.03
    marker_m: float = 0.022
    board_xyz_m: tuple[float, float, float] = (0.25, 0.0, 0.0)
    camera_xyz_m: tuple[float, float, float] = (0.5, 0.0, 0.4)
    image_size: tuple[int, int] = (1280, 960)
    focal_px: float = 1100.0
    pixel_noise_sd: float = 0.0
    board_px: int = 1000

    @cached_property
    def board(self) -> cv2.aruco.CharucoBoard:
        """OpenCV's board model (DICT_4X4_50)."""
        dictionary = cv2.aruco.getPredefinedDictionary(cv2.aruco.DICT_4X4_50)
        n = self.squares
        return cv2.aruco.CharucoBoard((n, n), self.square_m, self.marker_m, dictionary)

    @property
    def camera_matrix(self) -> np.ndarray:
        """K (3×3)."""
        w, h = self.image_size
        return np.array([[self.focal_px, 0, w / 2], [0, self.focal_px, h / 2], [0, 0, 1.0]])

    @cached_property
    def board_image(self) -> np.ndarray:
        """The board picture (board_px × board_px, uint8), no margin."""
        return self.board.generateImage((self.board_px, self.board_px), marginSize=0)

    @property
    def _pixel_from_board(self) -> np.ndarray:
        """Homography from board coordinates (m, z = 0) to board-image pixels: OpenCV draws
        the board to scale with x to the right and y downwards, pixel centres at integers."""
        s = self.board_px / (self.squares * self.square_m)
        return np.array([[s, 0.0, -0.5], [0.0, s, -0.5], [0.0, 0.0, 1.0]])

    @property
    def mount(self) -> np.ndarray:
        """T_D,B: the board frame in F_D (4×4), the board's centre at `board_xyz_m`.

        OpenCV's board frame has x right, y down on the printed face, so its z axis points
        into the board; face up means board z = −z of F_D (a half turn about x)."""
        half = self.squares * self.square_m / 2.0
        t = np.eye(4)
        t[:3, :3] = np.diag([1.0, -1.0, -1.0])
        t[:3, 3] = np.asarray(self.board_xyz_m) - t[:3, :3] @ np.array([half, half, 0.0])
        return t

    @property
    def camera(self) -> np.ndarray:
        """T_DG,CT: the camera in F_DG (4×4), aimed at the goal board centre."""
        return _look_at(np.asarray(self.camera_xyz_m), np.asarray(self.board_xyz_m))

    def render(self, camera_from_board: np.ndarray, rng: np.random.Generator | None = None):
        """The camera image (H, W) uint8 of the board at pose T_CT,B (4×4).

        Exact homography K·[r₁ r₂ t] warp at twice the resolution, area-averaged down; grey
        background; `pixel_noise_sd` Gaussian grey-level noise when `rng` is given."""
        k2 = self.camera_matrix.copy()
        k2[:2] *= 2.0
        k2[:2, 2] += 0.5  # pixel centres: x2 = 2·x1 + 0.5
        rt = camera_from_board[:3][:, [0, 1, 3]]
        h = k2 @ rt @ np.linalg.inv(self._pixel_from_board)
        w, hh = self.image_size
        big = cv2.warpPerspective(
            self.board_image, h, (2 * w, 2 * hh), flags=cv2.INTER_LINEAR,
            borderMode=cv2.BORDER_CONSTANT, borderValue=128,
        )  # fmt: skip
        img = cv2.resize(big, (w, hh), interpolation=cv2.INTER_AREA).astype(float)
        if rng is not None and self.pixel_noise_sd > 0:
            img += rng.normal(0.0, self.pixel_noise_sd, img.shape)
        return np.clip(np.round(img), 0, 255).astype(np.uint8)

    def measure(self, image: np.ndarray) -> MeasuredPose:
        """T_CT,B from one image: ChArUco corners (`CharucoDetector`, refined with
        `cornerSubPix` in a 11×11 px window) and `solvePnP`."""
        corners, ids, _, _ = cv2.aruco.CharucoDetector(self.board).detectBoard(image)
        if ids is None or len(ids) < 6:
            return MeasuredPose(None, 0 if ids is None else len(ids))
        stop = (cv2.TERM_CRITERIA_EPS + cv2.TERM_CRITERIA_MAX_ITER, 100, 1e-4)
        corners = cv2.cornerSubPix(image, corners.astype(np.float32), (5, 5), (-1, -1), stop)
        obj, img = self.board.matchImagePoints(corners, ids)
        ok, rvec, tvec = cv2.solvePnP(obj, img, self.camera_matrix, None)
        if not ok:
            return MeasuredPose(None, len(ids))
        t = np.eye(4)
        t[:3, :3] = cv2.Rodrigues(rvec)[0]
        t[:3, 3] = tvec.ravel()
        return MeasuredPose(t, len(ids))

    def true_board_pose(self, error: np.ndarray) -> np.ndarray:
        """T_CT,B when the robot stands at docking error ξ = (x m, y m, θ rad) from its goal."""
        return np.linalg.inv(self.camera) @ planar_to_se3(*error) @ self.mount

    def error_from(self, reference: np.ndarray, current: np.ndarray) -> np.ndarray:
        """Eq. 6.11: ξ̃ = (x m, y m, θ rad) of T_DG,D = T_DG,BG · T_CT,BG⁻¹ · T_CT,B · T_D,B⁻¹."""
        t = self.mount @ np.linalg.inv(reference) @ current @ np.linalg.inv(self.mount)
        return np.array([t[0, 3], t[1, 3], math.atan2(t[1, 0], t[0, 0])])

    @cached_property
    def reference(self) -> np.ndarray:
        """T_CT,BG measured on a noise-free render at the goal (the study's manual reference)."""
        pose = self.measure(self.render(self.true_board_pose(np.zeros(3)))).transform
        if pose is None:
            raise RuntimeError("ChArUco board not found at the goal pose: check the rig")
        return pose

    def measure_error(
        self, error: np.ndarray, rng: np.random.Generator | None = None
    ) -> np.ndarray | None:
        """The measured docking error ξ̃ (x m, y m, θ rad) for a true error ξ, or None when
        the board is not found."""
        pose = self.measure(self.render(self.true_board_pose(error), rng)).transform
        return None if pose is None else self.error_from(self.reference, pose)
