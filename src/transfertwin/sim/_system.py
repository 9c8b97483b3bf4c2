"""A compiled virtual transfer system: TM^V + TU^V + one object, and its virtual HAL.

`VirtualTransferSystem` owns one `MjModel`/`MjData` pair (belt drives live in the model's
`geom_surfacevel`, so a system is not shared between threads). It exposes the same
hardware-abstraction surface a real unit has (`MujocoUnitHAL`: belt drives and light
barriers), a simulated clock, and the state readout of the object (AABB in F_T computed
from the hull vertices at camera rate).
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable

import mujoco
import numpy as np

from transfertwin.objects import merge_hulls
from transfertwin.sim._config import DockingError, SceneConfig
from transfertwin.sim._docking import tu_pose_in_tip_frame
from transfertwin.sim._names import OBJECT_BODY, OBJECT_JOINT, TU_BODY, barrier_sensor, belt_geom
from transfertwin.sim._scene import BARRIERS, BELTS, UNITS, build_spec

__all__ = [
    "UNIT_LOAD_X_M",
    "MujocoUnitHAL",
    "SimClock",
    "SimulationUnstable",
    "VirtualTransferSystem",
    "object_quat",
    "outer_vertices",
    "tu_quat",
]

#: Where a station puts an object down on a transfer unit's belts for a pick-up: its centre
#: this far (m) into the unit from the unit's end at the gap.
UNIT_LOAD_X_M = 0.25

_SENSORS_OFF = int(mujoco.mjtDisableBit.mjDSBL_SENSOR)
# The warnings on which MuJoCo resets the data: bad qpos, qvel and qacc (consecutive codes).
_UNSTABLE = slice(int(mujoco.mjtWarning.mjWARN_BADQPOS), int(mujoco.mjtWarning.mjWARN_BADQACC) + 1)
_PULLEYS = ("pulley_start", "pulley_end")
# The ufunc's reduction itself: ndarray.max first passes through a Python wrapper.
_MAX = np.maximum.reduce


def outer_vertices(verts: np.ndarray) -> np.ndarray:
    """The vertices of the convex hull of `verts` (all of them if qhull cannot build one)."""
    from scipy.spatial import ConvexHull, QhullError

    try:
        return np.ascontiguousarray(verts[ConvexHull(verts).vertices])
    except (QhullError, ValueError):
        return verts


def tu_quat(yaw_rad: float, pitch_rad: float = 0.0, roll_rad: float = 0.0) -> np.ndarray:
    """Orientation (w, x, y, z) of the docked TU frame in F_T: the docking yaw about z, then
    the unmeasured tilt in the TU's own axes — pitch about its y axis (the gap line; positive
    raises the far end) and roll about its x axis (positive raises the left belt)."""
    yaw = np.array([math.cos(yaw_rad / 2), 0.0, 0.0, math.sin(yaw_rad / 2)])
    if pitch_rad == 0.0 and roll_rad == 0.0:
        return yaw
    # A rotation by -pitch about +y lifts points at +x (the far end).
    pitch = np.array([math.cos(-pitch_rad / 2), 0.0, math.sin(-pitch_rad / 2), 0.0])
    roll = np.array([math.cos(roll_rad / 2), math.sin(roll_rad / 2), 0.0, 0.0])
    tmp, out = np.empty(4), np.empty(4)
    mujoco.mju_mulQuat(tmp, yaw, pitch)
    mujoco.mju_mulQuat(out, tmp, roll)
    return out


class SimulationUnstable(RuntimeError):  # noqa: N818 - names a state, not an error kind
    """The physics diverged (non-finite state or solver warnings), or, with the scene's
    `PhysicsConfig.guard` on, did something implausible (launch, energy jump, deep
    penetration)."""


def object_quat(face: str, theta_rad: float) -> np.ndarray:
    """Orientation (w, x, y, z) of F_O for a face and yaw (Eq. 5.5).

    'front' is F_O with z up; 'back' is the object turned over by 180° about its x axis.
    The yaw θ is applied about the world z axis after that.
    """
    yaw = np.array([math.cos(theta_rad / 2), 0.0, 0.0, math.sin(theta_rad / 2)])
    if face == "front":
        return yaw
    flip = np.array([0.0, 1.0, 0.0, 0.0])
    out = np.empty(4)
    mujoco.mju_mulQuat(out, yaw, flip)
    return out


class SimClock:
    """Simulated time: `wait` steps the physics."""

    def __init__(self, system: VirtualTransferSystem) -> None:
        self._system = system
        self._t0 = 0.0
        self._last, self._steps = (math.nan, math.nan), 1  # wait's last (dt, timestep), steps

    def now(self) -> float:
        """Seconds since the clock was last started."""
        return float(self._system.data.time) - self._t0

    def start(self) -> None:
        """Set the clock's zero to the current simulation time."""
        self._t0 = float(self._system.data.time)

    def wait(self, dt_s: float) -> None:
        """Advance the simulation by `dt_s` (rounded to whole physics steps, at least 1)."""
        system = self._system
        timestep = system._opt.timestep
        if (dt_s, timestep) != self._last:  # a controller waits the same period each sample
            self._last, self._steps = (dt_s, timestep), max(1, round(dt_s / timestep))
        system.step(self._steps)
        for listener in system.step_listeners:
            listener()


class TrackingClock(SimClock):
    """`SimClock` that tells a track about every start (`track.starts`, the simulation time)
    and, after every wait, lets it sample the system (`track.sample(system)`): the physics
    is `SimClock`'s own, bit for bit (replays and recordings of experiments)."""

    def __init__(self, system: VirtualTransferSystem, track) -> None:
        super().__init__(system)
        self._track = track

    def start(self) -> None:
        super().start()
        self._track.starts.append(float(self._system.data.time))

    def wait(self, dt_s: float) -> None:
        super().wait(dt_s)
        self._track.sample(self._system)


def _axle_in_geom_frame(model: mujoco.MjModel, geom: int) -> np.ndarray:
    """The unit's y axis (a pulley's axle) in `geom`'s compiled frame, (3,)."""
    if model.geom_type[geom] == mujoco.mjtGeom.mjGEOM_CYLINDER:
        return np.array([0.0, 0.0, 1.0])  # exactly the cylinder's axis
    rot = np.empty(9)
    mujoco.mju_quat2Mat(rot, model.geom_quat[geom])
    return rot.reshape(3, 3)[1].copy()  # row 1 of R = R^T e_y


class MujocoUnitHAL:
    """Virtual HAL of one unit ('tm' or 'tu'): two belt drives and two light barriers.

    Speeds are surface speeds (m/s) along the unit's own x axis; positive moves objects
    towards the TU for the TM and away from the TM for the TU.
    """

    def __init__(self, system: VirtualTransferSystem, unit: str) -> None:
        if unit not in UNITS:
            raise ValueError(f"unknown unit {unit!r}")
        self.name = unit
        self._system = system
        model = system.model
        self._r = system.cfg.layout.pulley_radius_m
        self._near, self._far = (
            int(model.sensor(barrier_sensor(unit, which)).adr[0]) for which in BARRIERS
        )
        self._beam_m = 2 * system.cfg.layout.belt_width_m + system.cfg.layout.belt_separation_m
        # A view made once stays current: MjData's arrays keep their memory (the system
        # makes new HALs when it attaches other data).
        self._sensordata = system.data.sensordata
        # Per belt: its geoms (deck, start and end pulley) and each pulley's axle (the unit's
        # y axis) in its compiled geom frame — the geom's z for a cylinder, wherever
        # MuJoCo's principal axes put it for a prism mesh.
        self._belt_rows: dict[str, tuple[list[int], np.ndarray]] = {}
        for belt in BELTS:
            rows = [model.geom(belt_geom(unit, belt, p)).id for p in ("deck", *_PULLEYS)]
            axles = np.array([_axle_in_geom_frame(model, gid) for gid in rows[1:]])
            self._belt_rows[belt] = (rows, axles)
        self._speeds = dict.fromkeys(BELTS, 0.0)

    def set_belt_speed(self, belt: str, speed_m_s: float) -> None:
        """Drive `belt` ('left'/'right') at `speed_m_s`; 0 stops it."""
        if belt not in BELTS:
            raise ValueError(f"unknown belt {belt!r}")
        rows, axles = self._belt_rows[belt]
        values = np.zeros((3, 6))  # deck, start pulley, end pulley
        values[0, 0] = speed_m_s
        values[1:, 3:] = (speed_m_s / self._r) * axles  # ω about each pulley's axle
        self._system.model.geom_surfacevel[rows] = values
        self._speeds[belt] = float(speed_m_s)

    def belt_speed(self, belt: str) -> float:
        """Commanded surface speed of `belt` (m/s)."""
        return self._speeds[belt]

    def barriers(self) -> dict[str, bool]:
        """Whether the 'near' and 'far' light barriers are interrupted."""
        values = self._sensordata.tolist()  # a handful of sensors: one call for all
        near, far = values[self._near], values[self._far]
        beam = self._beam_m
        return {"near": 0.0 <= near < beam, "far": 0.0 <= far < beam}


class VirtualTransferSystem:
    """TM^V, TU^V and one object, compiled once and reused across experiments.

    Args:
        hulls: Object convex hulls in F_O, each (k, 3) (m).
        mass_kg, com_m, inertia_kg_m2: Object mass properties in F_O; the scene's
            `com_offset_m` shifts the centre of mass along x.
        cfg: Scene configuration.
        feature_hulls: How many of the last `hulls` are features (a proxy's protrusions),
            whose friction is the scene's `feature_mu` when that is set.

    With the scene's hull budget set (`PhysicsConfig.max_hulls`), the hulls are merged
    down to it first; the readout's AABB then comes from the merged hulls' vertices, which
    are a subset of the original ones, so it is unchanged.
    """

    def __init__(
        self,
        hulls: tuple[np.ndarray, ...],
        mass_kg: float,
        com_m: np.ndarray,
        inertia_kg_m2: np.ndarray,
        cfg: SceneConfig,
        feature_hulls: int = 0,
    ) -> None:
        self.cfg = cfg
        if cfg.physics.max_hulls is not None:
            hulls = merge_hulls(hulls, cfg.physics.max_hulls, keep_last=feature_hulls)
        com_m = np.asarray(com_m, dtype=float) + np.array([cfg.com_offset_m, 0.0, 0.0])
        self.model = self._spec(hulls, mass_kg, com_m, inertia_kg_m2, cfg, feature_hulls).compile()
        self.data = mujoco.MjData(self.model)
        self._opt = self.model.opt  # bound once: read at every wait and step
        self._body = self.model.body(OBJECT_BODY).id
        joint = self.model.joint(OBJECT_JOINT)
        self._qadr = int(joint.qposadr[0])
        self._vadr = int(joint.dofadr[0])
        self._tu_mocap = int(self.model.body(TU_BODY).mocapid[0])
        self._verts = np.concatenate([np.asarray(h, dtype=float) for h in hulls], axis=0)
        self._com = np.asarray(com_m, dtype=float)
        # The readout's one product per sample, R @ columns (3, 2k + 2): the AABB of a point
        # set is the AABB of its convex hull's vertices, so the first k columns are only
        # those (exact, typically a quarter of all hull vertices), the next k their
        # negatives (R(-v) = -(Rv) exactly, so one max-reduction gives both ends of the
        # box); then the COM (R c) and the body's x axis (R e_x: the first column of R,
        # whose yaw is θ).
        outer = outer_vertices(self._verts)
        self._n_outer = len(outer)
        self._readout_t = np.ascontiguousarray(
            np.vstack([outer, -outer, self._com, (1.0, 0.0, 0.0)]).T
        )
        self.tu_pose = (cfg.gap_m, 0.0, 0.0)
        # Implausible-event guard (PhysicsConfig.guard): highest COM height and mechanical
        # energy at the last check, cleared whenever the object is placed or the TU moves.
        self._guard = bool(cfg.physics.guard)
        self._inertia = self.model.body_inertia[self._body].copy()
        self._mass = float(self.model.body_mass[self._body])
        self._g = float(-self.model.opt.gravity[2])
        self._attach_data(self.data)

    def _spec(self, hulls: tuple[np.ndarray, ...], mass_kg: float, com_m: np.ndarray,
              inertia_kg_m2: np.ndarray, cfg: SceneConfig,
              feature_hulls: int) -> mujoco.MjSpec:  # fmt: skip
        """The scene's spec before compiling (`build_spec`); a subclass may add to it (the
        emulated plant's jointed parts and sagging belts). The object's free joint and the
        readout stay the object body's."""
        return build_spec(hulls, mass_kg, com_m, inertia_kg_m2, cfg, feature_hulls=feature_hulls)

    def _attach_data(self, data: mujoco.MjData) -> None:
        """Make `data` this system's state: the readout's views, the units' HALs, the clock
        and the per-run counters all refer to it (a batch lane attaches its own)."""
        self.data = data
        self._bind_views()
        self.tm = MujocoUnitHAL(self, "tm")
        self.tu = MujocoUnitHAL(self, "tu")
        self.clock = SimClock(self)
        self.steps_taken = 0
        # Engine accounting over the system's life (benchmarks: overhead vs raw mj_step).
        self.engine_steps = 0
        self.engine_seconds = 0.0
        # Called after every clock wait: lets a live CPS publish sensor values (barriers).
        self.step_listeners: list[Callable[[], None]] = []
        self._vel6 = np.zeros(6)
        self._guard_reset()

    def _bind_views(self) -> None:
        """Views into `data` read at every sample (the readout's hot path): MjData's arrays
        keep their memory for the data's life, so a view made once stays current."""
        d = self.data
        self._pos = d.xpos[self._body]
        self._rot = d.xmat[self._body].reshape(3, 3)
        self._qpos7 = d.qpos[self._qadr : self._qadr + 7]
        self._qvel6 = d.qvel[self._vadr : self._vadr + 6]
        self._unstable = d.warning.number[_UNSTABLE]  # a view: the counts stay current
        k = self._n_outer
        self._pts = np.empty_like(self._readout_t)
        self._pts_ends = self._pts[:, : 2 * k].reshape(3, 2, k)  # a view: (axis, +/-, vertex)
        self._pts_extra = self._pts[:, 2 * k :]
        self._ends = np.empty((3, 2))  # per axis: max, -min

    def _guard_reset(self) -> None:
        self._z_top = -math.inf
        self._energy: float | None = None

    @property
    def timestep_s(self) -> float:
        """The physics step (s): what a clock wait is counted in (engine-neutral; an
        emulated plant's other engine has it too)."""
        return self._opt.timestep

    # -- set-up ---------------------------------------------------------------------------
    def reset(self, docking_error: DockingError) -> None:
        """Stop all belts, clear the state and dock the TU with `docking_error`."""
        mujoco.mj_resetData(self.model, self.data)
        for hal in (self.tm, self.tu):
            for belt in BELTS:
                hal.set_belt_speed(belt, 0.0)
        self.dock(docking_error)
        self.steps_taken = 0

    def dock(self, docking_error: DockingError) -> None:
        """Move the TU to where it lies for `docking_error` (Eq. 6.11), keeping the object.

        Used when a transport module docks at another unit with an object on board.
        """
        x, y, yaw = tu_pose_in_tip_frame(
            docking_error, self.cfg.gap_m, self.cfg.layout.tip_to_centre_m
        )
        self.tu_pose = (x, y, yaw)
        layout = self.cfg.layout
        self.data.mocap_pos[self._tu_mocap] = (x, y, layout.tu_height_offset_m)
        self.data.mocap_quat[self._tu_mocap] = tu_quat(
            yaw, math.radians(layout.tu_pitch_deg), math.radians(layout.tu_roll_deg)
        )
        mujoco.mj_forward(self.model, self.data)
        self._guard_reset()

    def place_on_unit(
        self, face: str, theta_rad: float, y_m: float = 0.0, dx_m: float = 0.0
    ) -> None:
        """Put the object down on the docked TU's belts where a pick-up starts: its AABB
        centre `UNIT_LOAD_X_M` (+ `dx_m`) into the unit from its end at the gap and `y_m`
        off the unit's centre line, yaw θ on `face` (the station's loading point; the
        floor's pick-ups and the pick-up E^V both start here)."""
        tx, ty, _ = self.tu_pose
        self.place(face, theta_rad, tx + UNIT_LOAD_X_M + dx_m, ty + y_m)

    def place(self, face: str, theta_rad: float, x_m: float, y_m: float) -> None:
        """Put the object with its AABB centre at (x, y), yaw θ on `face`, just above the belt."""
        quat = object_quat(face, theta_rad)
        rot = np.empty(9)
        mujoco.mju_quat2Mat(rot, quat)
        pts = self._verts @ rot.reshape(3, 3).T
        lo, hi = pts.min(axis=0), pts.max(axis=0)
        centre = 0.5 * (lo + hi)
        drop = self.cfg.placement.drop_height_m
        pos = np.array([x_m - centre[0], y_m - centre[1], -lo[2] + drop])
        q = self.data.qpos
        q[self._qadr : self._qadr + 3] = pos
        q[self._qadr + 3 : self._qadr + 7] = quat
        self.data.qvel[self._vadr : self._vadr + 6] = 0.0
        mujoco.mj_forward(self.model, self.data)
        self._guard_reset()

    # -- stepping -------------------------------------------------------------------------
    def step(self, n: int) -> None:
        """Advance `n` physics steps; raise `SimulationUnstable` if the state diverges."""
        t0 = time.perf_counter()
        if n > 1:
            # Sensors (the light barriers' rangefinders, ~12 % of a step) change nothing in
            # the dynamics and are read only after the last step: the steps before it skip
            # them, so the results are the same bits (docs/speed.md, lever f).
            opt = self._opt
            flags = opt.disableflags
            opt.disableflags = flags | _SENSORS_OFF
            try:
                mujoco.mj_step(self.model, self.data, nstep=n - 1)
            finally:
                opt.disableflags = flags
        mujoco.mj_step(self.model, self.data, nstep=min(n, 1))
        self.engine_seconds += time.perf_counter() - t0
        self.engine_steps += n
        self.steps_taken += n
        # MuJoCo resets the data when it meets a bad position, velocity or acceleration, so
        # its warning counts are the signal; a NaN or infinity anywhere in the pose makes the
        # sum non-finite (as does a pose beyond 1e308 m, which has diverged all the same).
        if sum(self._unstable.tolist()) or not math.isfinite(sum(self._qpos7.tolist())):
            raise SimulationUnstable(f"physics diverged at t={self.data.time:.3f} s")
        if self._guard:
            self._check_plausible()

    def _check_plausible(self) -> None:
        """Raise `SimulationUnstable` on an implausible event (`PhysicsConfig.guard`)."""
        ph, d = self.cfg.physics, self.data
        mujoco.mj_objectVelocity(
            self.model, d, mujoco.mjtObj.mjOBJ_BODY, self._body, self._vel6, 1
        )  # at the COM, in the principal axes
        w, v = self._vel6[:3], self._vel6[3:]
        speed = math.sqrt(float(v @ v))
        z = float(d.xipos[self._body, 2])
        self._z_top = max(self._z_top, z)
        fall = math.sqrt(2 * self._g * (self._z_top - z))
        limit = ph.guard_speed_factor * self.cfg.layout.belt_speed_m_s + fall
        t = f"t={d.time:.3f} s"
        if speed > limit:
            raise SimulationUnstable(
                f"implausible: object speed {speed:.2f} m/s above {limit:.2f} m/s at {t}"
            )
        energy = 0.5 * self._mass * speed**2 + 0.5 * float(self._inertia @ (w * w))
        energy += self._mass * self._g * z
        if self._energy is not None:
            rise = energy - self._energy
            if rise > ph.guard_energy_j_per_kg * self._mass:
                raise SimulationUnstable(f"implausible: energy jump {rise:.3f} J at {t}")
        self._energy = energy
        if d.ncon:
            dist = d.contact.dist[: d.ncon]
            k = int(np.argmin(dist))
            if -dist[k] > ph.guard_penetration_m:
                raise SimulationUnstable(
                    f"implausible: contact penetration {-dist[k] * 1000:.1f} mm at {t}"
                )

    # -- readout --------------------------------------------------------------------------
    def object_pose(self) -> tuple[np.ndarray, np.ndarray]:
        """Object body position (3,) and rotation matrix (3, 3) in F_T."""
        return (
            self.data.xpos[self._body].copy(),
            self.data.xmat[self._body].reshape(3, 3).copy(),
        )

    def object_qpos(self) -> np.ndarray:
        """The object's free-joint coordinates (7,): position and quaternion."""
        return self.data.qpos[self._qadr : self._qadr + 7].copy()

    def set_object_qpos(self, qpos: np.ndarray) -> None:
        """Restore a recorded object pose (for rendering) and recompute kinematics."""
        self.data.qpos[self._qadr : self._qadr + 7] = qpos
        mujoco.mj_forward(self.model, self.data)

    @property
    def time_s(self) -> float:
        """Simulated seconds since the model was compiled (MuJoCo's ``data.time``), which
        `clock.start` does not zero."""
        return float(self.data.time)

    def possessing_unit(self, com_xy: np.ndarray) -> int:
        """0 (TM) or 1 (TU): the side of the gap's centre line the COM projects onto.

        The centre line runs half-way between the TM tip line x = 0 and the TU's near
        belt end, which the docking error may shift and turn.
        """
        tx, ty, yaw = self.tu_pose
        x_tu_end = tx - (com_xy[1] - ty) * math.tan(yaw)
        return int(com_xy[0] > 0.5 * x_tu_end)

    def observe(self) -> np.ndarray:
        """(a, x, y, z, s_x, s_y, s_z, θ) of the object in F_T (Eq. 5.4 without f, c, t).

        The AABB comes from the hull vertices; θ is the yaw of the object's x axis (rad).
        """
        np.dot(self._rot, self._readout_t, out=self._pts)  # BLAS gemm, less dispatch than matmul
        # One reduction over contiguous rows: per axis max(Rv) and max(-Rv) = -min(Rv).
        (hx, nlx), (hy, nly), (hz, nlz) = _MAX(self._pts_ends, axis=2, out=self._ends).tolist()
        lx, ly, lz = -nlx, -nly, -nlz
        # The rest in Python floats: the same IEEE operations as on arrays, fewer calls.
        (cx, ex), (cy, ey), _ = self._pts_extra.tolist()  # R c and R e_x
        px, py, pz = self._pos.tolist()
        return np.array(
            [
                self.possessing_unit((cx + px, cy + py)),
                0.5 * (lx + hx) + px,
                0.5 * (ly + hy) + py,
                0.5 * (lz + hz) + pz,
                0.5 * (hx - lx),
                0.5 * (hy - ly),
                0.5 * (hz - lz),
                math.atan2(ey, ex),
            ]
        )

    def object_rest_speed(self) -> float:
        """Body-origin speed plus 0.1 m x angular speed (m/s): 0 only for an object at rest."""
        v = self._qvel6
        return math.hypot(v[0], v[1], v[2]) + 0.1 * math.hypot(v[3], v[4], v[5])

    def object_speed(self) -> float:
        """Linear speed (m/s) of the object's body origin."""
        return float(np.linalg.norm(self.data.qvel[self._vadr : self._vadr + 3]))
