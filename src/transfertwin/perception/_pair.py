"""A scene with two copies of one object on the TM belts, for the separation study (Sec. 5.5).

The virtual transfer system holds one object. To see how close two objects may lie before
the detector merges them (Fig. 5.17), `pair_scene` compiles the system's scene (`build_spec`)
with a second, static copy of the object's hulls on a mocap body. Nothing is simulated:
both objects are laid exactly onto the belt surface (lowest vertex at z = 0) and only
rendered.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import mujoco
import numpy as np

from transfertwin.perception._aabb import AABB
from transfertwin.sim import (
    OBJECT_JOINT,
    TU_BODY,
    SceneConfig,
    build_spec,
    object_hull,
    object_quat,
)

__all__ = ["PairScene", "pair_scene"]

_SECOND = "object_copy"


@dataclass
class PairScene:
    """Two copies of an object; `place` lays them along x with a clear gap between them.

    Attributes:
        model, data: The compiled scene (world = F_T).
        verts: (n, 3) the object's hull vertices in F_O.
    """

    model: mujoco.MjModel
    data: mujoco.MjData
    verts: np.ndarray

    def posed_verts(self, face: str, theta_rad: float) -> tuple[np.ndarray, np.ndarray]:
        """The orientation (w, x, y, z) for `face` and yaw θ, and the vertices turned by it."""
        quat = object_quat(face, theta_rad)
        rot = np.empty(9)
        mujoco.mju_quat2Mat(rot, quat)
        return quat, self.verts @ rot.reshape(3, 3).T

    def place(
        self, face: str, theta_rad: float, centre_x_m: float, gap_m: float, y_m: float = 0.0
    ) -> tuple[AABB, AABB]:
        """Lay both objects on `face` with yaw θ, one behind the other along x, their AABBs
        `gap_m` apart and centred on x = `centre_x_m`, y = `y_m`. Returns their true AABBs."""
        quat, pts = self.posed_verts(face, theta_rad)
        lo, hi = pts.min(axis=0), pts.max(axis=0)
        length = hi[0] - lo[0]
        boxes = []
        positions = []
        for sign in (-1.0, 1.0):
            cx = centre_x_m + sign * 0.5 * (length + gap_m)
            origin = np.array([cx, y_m, 0.0]) - 0.5 * (lo + hi) * [1, 1, 0] - [0, 0, lo[2]]
            positions.append(origin)
            boxes.append(AABB.of_points(pts + origin))
        joint = self.model.joint(OBJECT_JOINT)
        adr = int(joint.qposadr[0])
        self.data.qpos[adr : adr + 3] = positions[0]
        self.data.qpos[adr + 3 : adr + 7] = quat
        mocap = int(self.model.body(_SECOND).mocapid[0])
        self.data.mocap_pos[mocap] = positions[1]
        self.data.mocap_quat[mocap] = quat
        mujoco.mj_forward(self.model, self.data)
        return boxes[0], boxes[1]


def pair_scene(hulls: tuple[np.ndarray, ...], cfg: SceneConfig | None = None) -> PairScene:
    """Compile the scene of `cfg` with the object of `hulls` twice (the copy is static)."""
    cfg = cfg if cfg is not None else SceneConfig()
    mass, com, inertia = 1.0, np.zeros(3), np.eye(3) * 1e-3  # rendering only
    spec = build_spec(hulls, mass, com, inertia, cfg)
    body = spec.worldbody.add_body(name=_SECOND, mocap=True)
    for k in range(len(hulls)):
        body.add_geom(type=mujoco.mjtGeom.mjGEOM_MESH, meshname=object_hull(k),
                      contype=0, conaffinity=0)  # fmt: skip
    model = spec.compile()
    data = mujoco.MjData(model)
    # The TU sits at its nominal docked pose (no docking error).
    tu = int(model.body(TU_BODY).mocapid[0])
    data.mocap_pos[tu] = (cfg.gap_m, 0.0, cfg.layout.tu_height_offset_m)
    data.mocap_quat[tu] = (1.0, 0.0, 0.0, 0.0)
    verts = np.concatenate([np.asarray(h, dtype=float) for h in hulls])
    scene = PairScene(model, data, verts)
    scene.place("front", math.pi / 2, -0.325, 0.1)
    return scene
