"""The transfer system in a second physics engine: PyBullet.

`BulletTransferSystem` is the system `transfertwin.sim.VirtualTransferSystem` is — TM^V,
TU^V docked with a docking error, one object on convex hulls — built in PyBullet
(Bullet 3, `pybullet.DIRECT`, one physics client per system) instead of MuJoCo, with the
surface `transfertwin.study.experiment.run_experiment` and a floor module's `Environment`
drive: `reset`, `dock`, `place`, `place_on_unit`, `clock` (`now`, `start`, `wait`) with
its `step_listeners`, `time_s`, `timestep_s`, `observe`, `object_rest_speed`,
`object_qpos`, and the units' HALs `tm`/`tu` (`set_belt_speed`, `belt_speed`, `barriers`);
not MuJoCo's `model`/`data`, so no depth camera renders it. An emulated plant of kind
'bullet' runs its experiments here, and a floor on it its transfers
(`transfertwin.plant.PlantPhysics`): another engine's contact detection
(GJK/EPA with persistent manifolds, collision margins), solver (sequential impulses with
ERP, not soft constraints) and friction model (one friction pyramid per contact point,
friction combined as the product of the two bodies' coefficients) is a structural
difference the twin's MuJoCo model class cannot represent.

The geometry comes from the same `SceneConfig` as the MuJoCo scene's (`unit_layout`: belt
spans and barrier positions; `LayoutConfig`: belt width, separation, pulley radius, TU
height step, pitch and roll; `gap_m`; the docking error through `tu_pose_in_tip_frame`
and `tu_quat`), so both engines build the same plant.

How the belts are modelled. Bullet has no surface velocity (MuJoCo's ``surfacevel``).
Each unit is one fixed-base multibody (the TM at F_T, the TU at its docked pose, moved with
`resetBasePositionAndOrientation`) whose links are, per belt, a deck box on a prismatic
joint along the unit's x and two end pulleys (cylinders of the pulley radius, axle along
the unit's y) on revolute joints. The deck is a treadmill: before every physics step its
joint is reset to position 0 with velocity v (the belt's speed), and a velocity motor of
a large force holds v through the step, so the deck never moves away but every contact
sees a surface moving at v; each pulley is reset the same way to ω = v / r (a cylinder
turned about its axle is the same shape). An object on a running belt is carried at the
belt's speed (tested: within 2 % after a second). The belts collide only with the object
(collision groups), never with each other, as MuJoCo's static and mocap geoms do not.

Contacts. Belts and pulleys carry the friction μ of the scene, the object 1.0: Bullet's
product of the two is μ. No restitution, rolling or spinning friction (MuJoCo's condim 3),
no damping of the object's motion. The object's hulls form one compound shape in its
principal frame (mass, centre of mass and the full inertia tensor of the plant's hidden
values), with a collision margin of 0.5 mm (`_MARGIN_M`). Bullet's contact stiffness is
per body, so the compliant features of the MuJoCo plant are as rigid as the rest here.
The light barriers are ray casts across both belts at the MuJoCo barriers' places; a
barrier is interrupted when the object cuts its beam.

Determinism: `reset` rebuilds the whole world in a reset simulation
(`resetSimulation`), so a run does not depend on what ran before in the same system (no
contact manifold or warm start survives), and the broadphase pairs are sorted
(``deterministicOverlappingPairs``): same inputs, same bits.

The plausibility guard (`PhysicsConfig.guard`) checks what MuJoCo's does: the object's
speed against the belt speed plus a free fall, its energy between two camera samples, the
deepest contact penetration, and a non-finite pose (`SimulationUnstable`).
"""

from __future__ import annotations

import contextlib
import math
import os
import sys
import tempfile
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np

from transfertwin.sim import (
    BARRIERS,
    BELTS,
    UNITS,
    DockingError,
    SceneConfig,
    SimulationUnstable,
    VirtualTransferSystem,
    object_quat,
    outer_vertices,
    tu_pose_in_tip_frame,
    tu_quat,
    unit_layout,
)

__all__ = ["BulletTransferSystem"]

_GRAVITY = 9.81  # MuJoCo's default gravity, as the MuJoCo scene has it
#: Deck and pulley masses (kg) and their motors' force limits (N, N·m): a 4 kg core on a deck
#: moves the deck by nothing measurable within a step, and the reset puts it back anyway.
_DECK_KG, _PULLEY_KG = 50.0, 5.0
_DECK_FORCE, _PULLEY_TORQUE = 1e5, 1e4
_FLOOR_Z = -0.6  # the MuJoCo scene's floor plane
#: The object's collision margin (m): Bullet's convex hulls are their vertices' hull grown
#: by it, and a resting hull sits on it. PyBullet's default of 1 mm lifted a core 1-2 mm
#: off the belt (MuJoCo's soft contacts sink it a fraction of a millimetre instead).
_MARGIN_M = 0.0005
#: Collision groups: the belts touch only the object; the floor only the object.
_BELTS_GROUP, _OBJECT_GROUP, _FLOOR_GROUP = 1, 2, 4
_pybullet = None


def _bullet():
    """The `pybullet` module, imported once with its build banner (written to stderr by
    its C code on import) kept off the terminal, where it would read as a warning."""
    global _pybullet
    if _pybullet is None:
        sys.stderr.flush()
        saved = os.dup(2)
        sink = os.open(os.devnull, os.O_WRONLY)
        try:
            os.dup2(sink, 2)
            import pybullet
        finally:
            os.dup2(saved, 2)
            os.close(saved)
            os.close(sink)
        _pybullet = pybullet
    return _pybullet


def _xyzw(wxyz: np.ndarray) -> tuple[float, float, float, float]:
    w, x, y, z = (float(v) for v in wxyz)
    return x, y, z, w


def _rot(wxyz: np.ndarray) -> np.ndarray:
    """Rotation matrix (3, 3) of a unit quaternion (w, x, y, z)."""
    w, x, y, z = (float(v) for v in wxyz)
    return np.array([
        [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
        [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
        [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
    ])  # fmt: skip


def _wxyz(rot: np.ndarray) -> np.ndarray:
    """Unit quaternion (w, x, y, z), w >= 0, of a rotation matrix."""
    from scipy.spatial.transform import Rotation

    x, y, z, w = Rotation.from_matrix(rot).as_quat()
    q = np.array([w, x, y, z])
    return -q if w < 0 else q


def _principal(inertia: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Principal moments (3,) and axes (3, 3, columns, a proper rotation) of a tensor."""
    moments, axes = np.linalg.eigh(0.5 * (inertia + inertia.T))
    if np.linalg.det(axes) < 0:
        axes[:, 2] = -axes[:, 2]
    return moments, axes


def _hull_obj(hulls: tuple[np.ndarray, ...]) -> str:
    """The hulls as one Wavefront OBJ text of one object per hull (PyBullet makes a
    compound of convex hulls of it)."""
    from scipy.spatial import ConvexHull

    lines, first = [], 1
    for k, verts in enumerate(hulls):
        lines.append(f"o hull_{k}")
        lines += [f"v {x!r} {y!r} {z!r}" for x, y, z in verts.tolist()]
        lines += [f"f {a + first} {b + first} {c + first}"
                  for a, b, c in ConvexHull(verts).simplices.tolist()]  # fmt: skip
        first += len(verts)
    return "\n".join(lines) + "\n"


class _BulletHAL:
    """Virtual HAL of one unit ('tm' or 'tu') in Bullet: two belt drives and two light
    barriers, speeds along the unit's x as `MujocoUnitHAL`'s. A plant's belts run
    `scale` times the commanded speed (its hidden belt-speed error); `belt_speed` reports
    the command, as a real drive's set-point does."""

    def __init__(self, system: BulletTransferSystem, unit: str, scale: float = 1.0) -> None:
        if unit not in UNITS:
            raise ValueError(f"unknown unit {unit!r}")
        self.name = unit
        self._system = system
        self._scale = float(scale)
        self._speeds = dict.fromkeys(BELTS, 0.0)

    def set_belt_speed(self, belt: str, speed_m_s: float) -> None:
        """Drive `belt` ('left'/'right') at `speed_m_s`; 0 stops it."""
        if belt not in BELTS:
            raise ValueError(f"unknown belt {belt!r}")
        self._system._drive(self.name, belt, speed_m_s * self._scale)
        self._speeds[belt] = float(speed_m_s)

    def belt_speed(self, belt: str) -> float:
        """Commanded surface speed of `belt` (m/s)."""
        return self._speeds[belt]

    def barriers(self) -> dict[str, bool]:
        """Whether the 'near' and 'far' light barriers are interrupted."""
        return self._system._barriers(self.name)


class _BulletClock:
    """Simulated time (`transfertwin.sim.SimClock`'s surface): `wait` steps the physics."""

    def __init__(self, system: BulletTransferSystem) -> None:
        self._system = system
        self._t0 = 0.0

    def now(self) -> float:
        """Seconds since the clock was last started."""
        return self._system.time_s - self._t0

    def start(self) -> None:
        """Set the clock's zero to the current simulation time."""
        self._t0 = self._system.time_s

    def wait(self, dt_s: float) -> None:
        """Advance the simulation by `dt_s` (rounded to whole physics steps, at least 1)."""
        system = self._system
        system.step(max(1, round(dt_s / system.timestep_s)))
        for listener in system.step_listeners:
            listener()


class BulletTransferSystem:
    """TM^V, TU^V and one object in PyBullet (see the module docstring).

    Args:
        hulls: Object convex hulls in F_O, each (k, 3) (m).
        mass_kg, com_m, inertia_kg_m2: Object mass properties in F_O (inertia about the
            centre of mass, in F_O's axes); the scene's `com_offset_m` shifts the centre
            of mass along x, as in MuJoCo.
        cfg: Scene configuration: geometry, μ, gap, timestep, solver iterations, placement,
            guard. MuJoCo-only settings (solver kind, cone, solref, solimp, multi-CCD,
            pulley facets, hull budget, feature friction and softness) have no Bullet
            counterpart and are not used.
        belt_speed_scale: Every belt runs this times its commanded speed (a plant's hidden
            belt-speed error; 1: exact).
    """

    def __init__(
        self,
        hulls: tuple[np.ndarray, ...],
        mass_kg: float,
        com_m: np.ndarray,
        inertia_kg_m2: np.ndarray,
        cfg: SceneConfig,
        belt_speed_scale: float = 1.0,
    ) -> None:
        self.cfg = cfg
        self._pb = _bullet()
        self._client = self._pb.connect(self._pb.DIRECT)
        self._mass = float(mass_kg)
        com = np.asarray(com_m, dtype=float) + np.array([cfg.com_offset_m, 0.0, 0.0])
        self._com = com
        self._moments, self._axes = _principal(np.asarray(inertia_kg_m2, dtype=float))
        self._hulls = tuple(np.asarray(h, dtype=float) for h in hulls)
        # Hull vertices in the body frame (the principal frame at the centre of mass):
        # v_B = A^T (v_O - c); Bullet's base pose is that frame's.
        self._obj_text = _hull_obj(tuple((h - com) @ self._axes for h in self._hulls))
        self._verts = np.concatenate(self._hulls, axis=0)
        self._outer = outer_vertices(self._verts)  # the AABB's points: the hull's corners
        self.tu_pose = (cfg.gap_m, 0.0, 0.0)
        self._speed_of: dict[tuple[str, str], float] = {(u, b): 0.0 for u in UNITS for b in BELTS}
        self._guard = bool(cfg.physics.guard)
        self.tm = _BulletHAL(self, "tm", belt_speed_scale)
        self.tu = _BulletHAL(self, "tu", belt_speed_scale)
        self.clock = _BulletClock(self)
        self.step_listeners: list[Callable[[], None]] = []
        self.engine_steps, self.engine_seconds, self.steps_taken = 0, 0.0, 0
        self._build()

    # -- the world ------------------------------------------------------------------------
    def _build(self) -> None:
        """(Re)build the world from nothing: engine settings, units, floor, object."""
        pb, c = self._pb, self._client
        pb.resetSimulation(physicsClientId=c)
        pb.setPhysicsEngineParameter(
            fixedTimeStep=self.cfg.physics.timestep_s, numSubSteps=0,
            numSolverIterations=self.cfg.physics.iterations,
            deterministicOverlappingPairs=1, physicsClientId=c,
        )  # fmt: skip
        pb.setGravity(0.0, 0.0, -_GRAVITY, physicsClientId=c)
        self.time_s = 0.0
        self._units = {unit: self._add_unit(unit) for unit in UNITS}
        floor = pb.createCollisionShape(pb.GEOM_BOX, halfExtents=[3.0, 3.0, 0.1],
                                        physicsClientId=c)  # fmt: skip
        self._floor = pb.createMultiBody(0.0, floor, basePosition=[0.0, 0.0, _FLOOR_Z - 0.1],
                                         physicsClientId=c)  # fmt: skip
        pb.setCollisionFilterGroupMask(self._floor, -1, _FLOOR_GROUP, _OBJECT_GROUP,
                                       physicsClientId=c)  # fmt: skip
        self._object = self._add_object()
        for unit in UNITS:
            for belt in BELTS:
                self._drive(unit, belt, self._speed_of[unit, belt])
        x, y, yaw = self.tu_pose
        self._pose_tu(x, y, yaw)
        self._guard_reset()

    def _add_unit(self, unit: str) -> int:
        """One unit as a fixed-base multibody: per belt a deck (prismatic treadmill joint)
        and two pulleys (revolute joints), in the order deck, start, end."""
        pb, c = self._pb, self._client
        layout = self.cfg.layout
        span, _, _ = unit_layout(layout, unit)
        r, half_w = layout.pulley_radius_m, 0.5 * layout.belt_width_m
        x0, x1 = span.x_start + r, span.x_end - r  # as `add_belt`: pulley axles at x0, x1
        deck_shape = pb.createCollisionShape(pb.GEOM_BOX, halfExtents=[0.5 * (x1 - x0), half_w, r],
                                             physicsClientId=c)  # fmt: skip
        pulley_shape = pb.createCollisionShape(pb.GEOM_CYLINDER, radius=r, height=2 * half_w,
                                               physicsClientId=c)  # fmt: skip
        z_to_y = (-math.sin(math.pi / 4), 0.0, 0.0, math.cos(math.pi / 4))  # axle along y
        masses, shapes, pos, orn, types, axes = [], [], [], [], [], []
        for belt in BELTS:
            y = layout.belt_centre_y(belt)
            masses += [_DECK_KG, _PULLEY_KG, _PULLEY_KG]
            shapes += [deck_shape, pulley_shape, pulley_shape]
            pos += [[0.5 * (x0 + x1), y, -r], [x0, y, -r], [x1, y, -r]]
            orn += [[0.0, 0.0, 0.0, 1.0], z_to_y, z_to_y]
            types += [pb.JOINT_PRISMATIC, pb.JOINT_REVOLUTE, pb.JOINT_REVOLUTE]
            axes += [[1.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.0, 0.0, 1.0]]
        n = len(masses)
        body = pb.createMultiBody(
            baseMass=0.0, baseCollisionShapeIndex=-1, linkMasses=masses,
            linkCollisionShapeIndices=shapes, linkVisualShapeIndices=[-1] * n,
            linkPositions=pos, linkOrientations=orn,
            linkInertialFramePositions=[[0.0, 0.0, 0.0]] * n,
            linkInertialFrameOrientations=[[0.0, 0.0, 0.0, 1.0]] * n,
            linkParentIndices=[0] * n, linkJointTypes=types, linkJointAxis=axes,
            physicsClientId=c,
        )  # fmt: skip
        for link in range(n):
            pb.changeDynamics(body, link, lateralFriction=self.cfg.mu, restitution=0.0,
                              rollingFriction=0.0, spinningFriction=0.0, linearDamping=0.0,
                              angularDamping=0.0, jointDamping=0.0,
                              activationState=pb.ACTIVATION_STATE_DISABLE_SLEEPING,
                              physicsClientId=c)  # fmt: skip
            pb.setCollisionFilterGroupMask(body, link, _BELTS_GROUP, _OBJECT_GROUP,
                                           physicsClientId=c)  # fmt: skip
        return body

    def _add_object(self) -> int:
        """The object: a compound of its convex hulls in the principal frame."""
        pb, c = self._pb, self._client
        with tempfile.TemporaryDirectory(prefix="transfertwin-bullet-") as tmp:
            path = Path(tmp) / "object.obj"
            path.write_text(self._obj_text)
            shape = pb.createCollisionShape(pb.GEOM_MESH, fileName=str(path), physicsClientId=c)
        body = pb.createMultiBody(self._mass, shape, basePosition=[0.0, 0.0, 0.5],
                                  physicsClientId=c)  # fmt: skip
        pb.changeDynamics(body, -1, lateralFriction=1.0, restitution=0.0, rollingFriction=0.0,
                          spinningFriction=0.0, linearDamping=0.0, angularDamping=0.0,
                          localInertiaDiagonal=self._moments.tolist(),
                          collisionMargin=_MARGIN_M,
                          activationState=pb.ACTIVATION_STATE_DISABLE_SLEEPING,
                          physicsClientId=c)  # fmt: skip
        pb.setCollisionFilterGroupMask(body, -1, _OBJECT_GROUP, _BELTS_GROUP | _FLOOR_GROUP,
                                       physicsClientId=c)  # fmt: skip
        return body

    def _drive(self, unit: str, belt: str, speed_m_s: float) -> None:
        """Set the surface speed of a belt's deck and pulleys (held by motors, and by the
        treadmill reset before every step)."""
        self._speed_of[unit, belt] = float(speed_m_s)
        k = 3 * BELTS.index(belt)
        omega = speed_m_s / self.cfg.layout.pulley_radius_m
        self._pb.setJointMotorControlArray(
            self._units[unit], [k, k + 1, k + 2], self._pb.VELOCITY_CONTROL,
            targetVelocities=[speed_m_s, omega, omega],
            forces=[_DECK_FORCE, _PULLEY_TORQUE, _PULLEY_TORQUE], physicsClientId=self._client,
        )  # fmt: skip

    def _pose_tu(self, x: float, y: float, yaw: float) -> None:
        layout = self.cfg.layout
        q = tu_quat(yaw, math.radians(layout.tu_pitch_deg), math.radians(layout.tu_roll_deg))
        self._tu_rot = _rot(q)
        self._tu_pos = np.array([x, y, layout.tu_height_offset_m])
        self._pb.resetBasePositionAndOrientation(
            self._units["tu"], self._tu_pos.tolist(), _xyzw(q), physicsClientId=self._client
        )

    def close(self) -> None:
        """Disconnect the physics client (the system is unusable afterwards)."""
        if self._client is not None and self._pb is not None:
            with contextlib.suppress(Exception):
                self._pb.disconnect(physicsClientId=self._client)
            self._client = None

    def __del__(self) -> None:
        with contextlib.suppress(Exception):
            self.close()

    def _guard_reset(self) -> None:
        self._z_top = -math.inf
        self._energy: float | None = None

    # -- set-up ---------------------------------------------------------------------------
    @property
    def timestep_s(self) -> float:
        """The physics step (s)."""
        return self.cfg.physics.timestep_s

    def reset(self, docking_error: DockingError) -> None:
        """Rebuild the world (nothing of an earlier run survives), all belts stopped, and
        dock the TU with `docking_error`."""
        self._speed_of = dict.fromkeys(self._speed_of, 0.0)
        for hal in (self.tm, self.tu):
            hal._speeds = dict.fromkeys(BELTS, 0.0)
        self._build()
        self.dock(docking_error)
        self.steps_taken = 0

    def dock(self, docking_error: DockingError) -> None:
        """Move the TU to where it lies for `docking_error` (Eq. 6.11), keeping the object."""
        x, y, yaw = tu_pose_in_tip_frame(
            docking_error, self.cfg.gap_m, self.cfg.layout.tip_to_centre_m
        )
        self.tu_pose = (x, y, yaw)
        self._pose_tu(x, y, yaw)
        self._guard_reset()

    #: Where a pick-up starts (the unit's loading point): `place` relative to `tu_pose`.
    place_on_unit = VirtualTransferSystem.place_on_unit

    def place(self, face: str, theta_rad: float, x_m: float, y_m: float) -> None:
        """Put the object with its AABB centre at (x, y), yaw θ on `face`, just above the
        belt (as `VirtualTransferSystem.place`)."""
        rot = _rot(object_quat(face, theta_rad))
        pts = self._verts @ rot.T
        lo, hi = pts.min(axis=0), pts.max(axis=0)
        centre = 0.5 * (lo + hi)
        drop = self.cfg.placement.drop_height_m
        origin = np.array([x_m - centre[0], y_m - centre[1], -lo[2] + drop])
        body_rot = rot @ self._axes
        pb, c = self._pb, self._client
        pb.resetBasePositionAndOrientation(self._object, (origin + rot @ self._com).tolist(),
                                           _xyzw(_wxyz(body_rot)), physicsClientId=c)  # fmt: skip
        pb.resetBaseVelocity(self._object, [0.0, 0.0, 0.0], [0.0, 0.0, 0.0], physicsClientId=c)
        self._guard_reset()

    # -- stepping -------------------------------------------------------------------------
    def step(self, n: int) -> None:
        """Advance `n` physics steps (each after the treadmill reset of every belt); raise
        `SimulationUnstable` if the state diverges or, with the guard on, is implausible."""
        pb, c = self._pb, self._client
        t0 = time.perf_counter()
        r = self.cfg.layout.pulley_radius_m
        resets = []
        for unit in UNITS:
            speeds = []
            for belt in BELTS:
                v = self._speed_of[unit, belt]
                speeds += [[v], [v / r], [v / r]]
            resets.append((self._units[unit], speeds))
        joints, zeros = list(range(6)), [[0.0]] * 6
        for _ in range(n):
            for body, speeds in resets:
                pb.resetJointStatesMultiDof(body, joints, zeros, speeds, physicsClientId=c)
            pb.stepSimulation(physicsClientId=c)
        self.time_s += n * self.timestep_s
        self.engine_seconds += time.perf_counter() - t0
        self.engine_steps += n
        self.steps_taken += n
        pos, _ = pb.getBasePositionAndOrientation(self._object, physicsClientId=c)
        if not math.isfinite(sum(pos)):
            raise SimulationUnstable(f"physics diverged at t={self.time_s:.3f} s")
        if self._guard:
            self._check_plausible()

    def _check_plausible(self) -> None:
        """Raise `SimulationUnstable` on an implausible event (`PhysicsConfig.guard`): the
        checks of `VirtualTransferSystem`'s guard."""
        pb, c = self._pb, self._client
        ph = self.cfg.physics
        (_, _, z), quat = pb.getBasePositionAndOrientation(self._object, physicsClientId=c)
        lin, ang = pb.getBaseVelocity(self._object, physicsClientId=c)
        speed = math.sqrt(sum(v * v for v in lin))
        self._z_top = max(self._z_top, z)
        fall = math.sqrt(2 * _GRAVITY * (self._z_top - z))
        limit = ph.guard_speed_factor * self.cfg.layout.belt_speed_m_s + fall
        t = f"t={self.time_s:.3f} s"
        if speed > limit:
            raise SimulationUnstable(
                f"implausible: object speed {speed:.2f} m/s above {limit:.2f} m/s at {t}"
            )
        rot = np.array(pb.getMatrixFromQuaternion(quat, physicsClientId=c)).reshape(3, 3)
        w = rot.T @ np.asarray(ang)  # in the principal axes
        energy = 0.5 * self._mass * speed**2 + 0.5 * float(self._moments @ (w * w))
        energy += self._mass * _GRAVITY * z
        rise = 0.0 if self._energy is None else energy - self._energy
        if rise > ph.guard_energy_j_per_kg * self._mass:
            raise SimulationUnstable(f"implausible: energy jump {rise:.3f} J at {t}")
        self._energy = energy
        contacts = pb.getContactPoints(bodyA=self._object, physicsClientId=c)
        if contacts:
            depth = -min(cp[8] for cp in contacts)
            if depth > ph.guard_penetration_m:
                raise SimulationUnstable(
                    f"implausible: contact penetration {depth * 1000:.1f} mm at {t}"
                )

    # -- readout --------------------------------------------------------------------------
    def _frame(self) -> tuple[np.ndarray, np.ndarray, list[float], list[float]]:
        """F_O's rotation and origin in F_T, and the body's linear (at the centre of mass)
        and angular velocity in F_T."""
        pb, c = self._pb, self._client
        pos, quat = pb.getBasePositionAndOrientation(self._object, physicsClientId=c)
        body_rot = np.array(pb.getMatrixFromQuaternion(quat, physicsClientId=c)).reshape(3, 3)
        rot = body_rot @ self._axes.T
        lin, ang = pb.getBaseVelocity(self._object, physicsClientId=c)
        return rot, np.asarray(pos) - rot @ self._com, list(lin), list(ang)

    def object_pose(self) -> tuple[np.ndarray, np.ndarray]:
        """Object body (F_O) position (3,) and rotation matrix (3, 3) in F_T."""
        rot, origin, _, _ = self._frame()
        return origin, rot

    def object_qpos(self) -> np.ndarray:
        """F_O's position and quaternion (w, x, y, z) in F_T (7,), as MuJoCo's free joint."""
        rot, origin, _, _ = self._frame()
        return np.concatenate([origin, _wxyz(rot)])

    possessing_unit = VirtualTransferSystem.possessing_unit  # reads only `tu_pose`

    def observe(self) -> np.ndarray:
        """(a, x, y, z, s_x, s_y, s_z, θ) of the object in F_T (Eq. 5.4 without f, c, t),
        the AABB from the hull vertices, as `VirtualTransferSystem.observe`."""
        rot, origin, _, _ = self._frame()
        pts = self._outer @ rot.T
        lo, hi = pts.min(axis=0), pts.max(axis=0)
        com = rot @ self._com + origin
        centre = 0.5 * (lo + hi) + origin
        half = 0.5 * (hi - lo)
        a = self.possessing_unit((float(com[0]), float(com[1])))
        return np.array([a, *centre.tolist(), *half.tolist(), math.atan2(rot[1, 0], rot[0, 0])])

    def object_rest_speed(self) -> float:
        """F_O origin's speed plus 0.1 m x angular speed (m/s), as MuJoCo's free joint
        velocity gives it: 0 only for an object at rest."""
        rot, _, lin, ang = self._frame()
        v = np.asarray(lin) - np.cross(ang, rot @ self._com)  # the velocity at F_O's origin
        return math.hypot(*v.tolist()) + 0.1 * math.hypot(*ang)

    def object_speed(self) -> float:
        """Linear speed (m/s) of the object's body origin (F_O)."""
        rot, _, lin, ang = self._frame()
        return float(np.linalg.norm(np.asarray(lin) - np.cross(ang, rot @ self._com)))

    def _barriers(self, unit: str) -> dict[str, bool]:
        """A unit's barriers: a ray across both belts at the MuJoCo barrier's place (from
        just outside the left belt towards -y, `barrier_height_m` above the belt), broken
        when the object cuts it within the beam's length."""
        layout = self.cfg.layout
        _, near, far = unit_layout(layout, unit)
        y_edge = layout.belt_separation_m / 2 + layout.belt_width_m + 0.01  # `add_light_barrier`
        beam = 2 * layout.belt_width_m + layout.belt_separation_m
        starts = np.array([[x, y_edge, layout.barrier_height_m] for x in (near, far)])
        ends = starts - np.array([0.0, beam, 0.0])
        if unit == "tu":
            starts = starts @ self._tu_rot.T + self._tu_pos
            ends = ends @ self._tu_rot.T + self._tu_pos
        hits = self._pb.rayTestBatch(starts.tolist(), ends.tolist(), physicsClientId=self._client)
        return {which: hit[0] == self._object for which, hit in zip(BARRIERS, hits, strict=True)}
