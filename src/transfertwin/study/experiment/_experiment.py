"""The virtual experiment E^V (Sec. 6.2.2, Eq. 6.16–6.18): there and, if that worked, back;
or the legs of a transport operation on a floor (`LEGS`).

Legs (`ExperimentSpec.leg`):

- ``round-trip`` (the study's, Eq. 6.18): the object in a pre-transfer state on the TM, the
  transfer TM → TU (y1) and, if it succeeded, back TU → TM (y2);
- ``pick-up``: the object put down on the TU at the station's loading point in the state's
  face, θ and lateral position (`VirtualTransferSystem.place_on_unit`), the transfer TU → TM
  (y1, Eq. 5.7–5.10 with a_pre = TU); y2 is None;
- ``operation``: the pick-up, then, if it succeeded, the module docked at the destination
  with a docking error of its own (``delivery_docking_error``) and the delivery TM → TU
  (y2) from the state the pick-up left: what a floor's transport operation does.

In every leg ``success`` is 1 when every transfer the leg runs succeeded.

`run_experiment(spec) -> ExperimentResult` is one picklable call that runs unchanged in a
loop, a process pool or a cluster task. Failures are data: a diverging simulation becomes
a result with status 'unstable', any other crash one with status 'error'.
"""

from __future__ import annotations

import dataclasses
import functools
import json
import logging
import math
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np

from transfertwin._atomic import file_stamp
from transfertwin._errors import InputError
from transfertwin.control import Clock, ObjectSensor, OTSController, TransferRecord, UnitHAL
from transfertwin.objects import ObjectModel, is_builtin_id, load_object
from transfertwin.ots import (
    POSITIONS,
    BeltPreTransferSet,
    BeltThresholds,
    TransferDirection,
    check_theta_deg,
    contains_state,
    experiment_pre_transfer_set,
    parse_conveyor,
    parse_face,
    pre_transfer_set,
)
from transfertwin.sim import DockingError, SceneConfig, SimulationUnstable, VirtualTransferSystem
from transfertwin.store import DOCKING_ERROR_COLUMNS, RESULT_COLUMNS

if TYPE_CHECKING:  # perception imports Open3D: loaded only when a run asks for it
    from transfertwin.perception import PerceptionConfig

__all__ = [
    "LEGS",
    "RESULT_COLUMNS",
    "SENSORS",
    "ExperimentResult",
    "ExperimentSpec",
    "Frame",
    "run_experiment",
    "scene_controller",
    "system_for",
]

log = logging.getLogger(__name__)

#: Where the OTS controller's object state comes from: the simulator's exact state
#: ('truth', `VirtualTransferSystem.observe`) or the TM's depth camera ('perception').
SENSORS: tuple[str, ...] = ("truth", "perception")
#: What one E^V runs (module docstring): the study's there and back, a floor's pick-up, or
#: a floor's whole operation (pick-up, then delivery).
LEGS: tuple[str, ...] = ("round-trip", "pick-up", "operation")


@dataclass(frozen=True)
class ExperimentSpec:
    """Everything one E^V needs; picklable.

    Attributes:
        object_ref: Built-in core id ('o1'..'o37') or a mesh path.
        face, conveyor, theta_deg: The pre-transfer state (Eq. 6.7–6.10); the position
            (x, y) follows from the conveyor (Eq. 6.3).
        docking_error: Docking error ξ applied to the TU (Eq. 6.11).
        scene: Virtual system configuration (instance + physics parameters).
        run: Repetition index r.
        seed: Seed of this experiment's random choices (placement perturbation).
        units: Length unit of a user mesh file.
        record: Keep the object's pose at every sample (for rendering).
        leg: What the experiment runs (`LEGS`): 'round-trip' (default), 'pick-up' or
            'operation'.
        delivery_docking_error: The docking error at the destination of an 'operation'
            (None: `docking_error` again); unused by the other legs.
    """

    object_ref: str
    face: str
    conveyor: str
    theta_deg: int
    docking_error: DockingError = field(default_factory=DockingError)
    scene: SceneConfig = field(default_factory=SceneConfig)
    run: int = 0
    seed: int = 0
    units: str = "m"
    record: bool = False
    leg: str = "round-trip"
    delivery_docking_error: DockingError | None = None

    def __post_init__(self) -> None:
        if self.leg not in LEGS:
            raise InputError(f"leg must be one of {', '.join(LEGS)}, got {self.leg!r}")
        object.__setattr__(self, "face", parse_face(self.face))
        object.__setattr__(self, "conveyor", parse_conveyor(self.conveyor))
        object.__setattr__(self, "theta_deg", check_theta_deg(self.theta_deg))
        if isinstance(self.seed, bool) or not isinstance(self.seed, int) or self.seed < 0:
            raise InputError(f"seed must be a non-negative integer, got {self.seed!r}")


@dataclass(frozen=True)
class Frame:
    """A recorded object pose: phase, time (s) and qpos (7,).

    phase is 'there' (TM → TU) or 'back' (TU → TM) in a round trip, 'pick-up' (TU → TM) or
    'delivery' (TM → TU) in the legs of an operation. t_s runs on the experiment's clock,
    as t_end_s does: 0 when the first transfer starts (settling before it is not counted);
    the return transfer goes on from t_end_1_s, so the last frame of a completed
    experiment is at t_end_s (at the stall time when a transfer stalled and ended early).
    """

    phase: str
    t_s: float
    qpos: tuple[float, ...]


@dataclass(frozen=True)
class ExperimentResult:
    """The outcome of one E^V, one row of the results table (the result columns of
    docs/architecture.md, "Contracts").

    y1, y2 and success are None when they were not determined (invalid pre-transfer
    state, unstable or crashed simulation); y2 is None when y1 = 0 (no return attempted).
    t_end_s is the sum of both transfers' t_end. States are (11,) vectors (Eq. 5.4).
    In a 'pick-up' or 'operation' (`LEGS`), y1 is the pick-up and y2 the delivery (None
    for a pick-up alone); the docking error columns are the pick-up's.
    """

    object_id: str
    face: str
    conveyor: str
    theta_deg: int
    run: int
    seed: int
    dock_err_x_mm: float
    dock_err_y_mm: float
    dock_err_theta_deg: float
    y1: int | None
    y2: int | None
    success: int | None
    t_end_s: float
    status: str
    t_end_1_s: float = math.nan
    t_end_2_s: float = math.nan
    message: str = ""
    state_pre: tuple[float, ...] = ()
    state_end_1: tuple[float, ...] = ()
    state_end_2: tuple[float, ...] = ()
    frames: tuple[Frame, ...] = field(default=(), repr=False, compare=False)

    def row(self) -> dict[str, object]:
        """The result as a flat row keyed by `RESULT_COLUMNS` (states as JSON lists)."""
        out: dict[str, object] = {}
        for name in RESULT_COLUMNS:
            value = getattr(self, name)
            if name.startswith("state_"):
                value = json.dumps([round(v, 6) for v in value]) if value else ""
            out[name] = value
        return out


@functools.lru_cache(maxsize=4)
def _object(ref: str, units: str, stamp: tuple[int, int, int] | None) -> ObjectModel:
    return load_object(ref, units=units)


def system_for(ref: str, units: str, scene: SceneConfig) -> VirtualTransferSystem:
    """The compiled virtual system for an object and scene, cached per process; a mesh or
    proxy file rewritten since it was cached is loaded again."""
    return _system_for(ref, units, scene, _stamp(ref))


def _stamp(ref: str) -> tuple[int, int, int] | None:
    """The file stamp the caches key on; none for a built-in id, which wins over a file of
    the same name (`load_object`), so no look at the disk per experiment."""
    return None if is_builtin_id(ref) else file_stamp(ref)


@functools.lru_cache(maxsize=2)
def _system_for(
    ref: str, units: str, scene: SceneConfig, stamp: tuple[int, int, int] | None
) -> VirtualTransferSystem:
    obj = _object(ref, units, stamp)
    return VirtualTransferSystem(
        obj.hulls, obj.mass.mass_kg, obj.mass.com_m, obj.mass.inertia_kg_m2, scene,
        feature_hulls=obj.feature_hulls,
    )  # fmt: skip


@functools.lru_cache(maxsize=8)
def _thresholds(t_max_s: float) -> BeltThresholds:
    """The belt thresholds with a scene's t_max (frozen: built and validated once)."""
    return BeltThresholds(t_max=t_max_s)


def scene_controller(
    scene: SceneConfig,
    tm: UnitHAL,
    tu: UnitHAL,
    sensor: ObjectSensor,
    clock: Clock,
    on_sample: Callable[[], None] | None = None,
) -> OTSController:
    """The OTS controller configured by a scene: its t_max, belt speed and camera rate."""
    return OTSController(
        tm, tu, sensor, clock,
        thresholds=_thresholds(scene.t_max_s),
        belt_speed_m_s=scene.layout.belt_speed_m_s,
        sample_period_s=scene.steps_per_sample() * scene.physics.timestep_s,
        on_sample=on_sample,
        stall_time_s=scene.stall_time_s,
        stall_tol_m=scene.stall_tol_m,
        stall_mode=scene.stall_mode,
    )  # fmt: skip


def _tuple(state: np.ndarray) -> tuple[float, ...]:
    return tuple(float(v) for v in state)


def _place_and_settle(system: VirtualTransferSystem, spec: ExperimentSpec) -> None:
    """Put the object into the requested state, perturbed by the seed, and let it settle:
    on the TM (a round trip) or at the TU's loading point (a pick-up, `LEGS`), at the
    conveyor's lateral position (Eq. 6.3)."""
    placement = spec.scene.placement
    rng = np.random.default_rng(spec.seed)
    dx, dy = rng.normal(0.0, placement.sigma_xy_m, size=2)
    dtheta = rng.normal(0.0, placement.sigma_theta_deg)
    x, y = POSITIONS[spec.conveyor]
    theta = math.radians(spec.theta_deg + dtheta)
    system.reset(spec.docking_error)
    if spec.leg == "round-trip":
        system.place(spec.face, theta, x + dx, y + dy)
    else:
        system.place_on_unit(spec.face, theta, y + dy, dx)
    settle(system, spec.scene)


def settle(system: VirtualTransferSystem, scene: SceneConfig) -> None:
    """Let the object settle with the belts stopped (`PlacementConfig`): for settle_time_s,
    or, with rest detection on, until it is at rest (at least min_settle_time_s)."""
    placement = scene.placement
    if placement.rest_speed_m_s is None:
        system.clock.wait(placement.settle_time_s)
        return
    dt = system.timestep_s
    total = max(1, round(placement.settle_time_s / dt))
    done = min(total, max(1, round(placement.min_settle_time_s / dt)))
    check = max(1, round(placement.rest_check_s / dt))
    system.clock.wait(done * dt)
    while done < total and system.object_rest_speed() >= placement.rest_speed_m_s:
        n = min(check, total - done)
        system.clock.wait(n * dt)
        done += n


#: Per leg: (direction, frame phase) of the first transfer and of the second (None: none).
_LEG_TRANSFERS = {
    "round-trip": ((TransferDirection.TM_TO_TU, "there"), (TransferDirection.TU_TO_TM, "back")),
    "pick-up": ((TransferDirection.TU_TO_TM, "pick-up"), None),
    "operation": ((TransferDirection.TU_TO_TM, "pick-up"), (TransferDirection.TM_TO_TU,
                                                            "delivery")),
}  # fmt: skip
#: Why a settled object cannot start a leg.
_NOT_PRE = {
    "round-trip": "settled state is not a pre-transfer state (Eq. 6.1)",
    "pick-up": "the object put down on the unit is not in a pre-transfer state of a pick-up "
               "(Eq. 5.7 with a_pre = TU)",
}  # fmt: skip
_NOT_PRE["operation"] = _NOT_PRE["pick-up"]


def _pre_set(leg: str, th: BeltThresholds) -> BeltPreTransferSet:
    """The set a leg's settled start state must lie in: the study's S_pre (Eq. 6.1) on the
    module for a round trip, Eq. 5.7's set on the unit (a_pre = TU) for a pick-up."""
    if leg == "round-trip":
        return experiment_pre_transfer_set(th)
    return pre_transfer_set(th, TransferDirection.TU_TO_TM)


def run_experiment(
    spec: ExperimentSpec,
    *,
    tu_hal: UnitHAL | None = None,
    system: VirtualTransferSystem | None = None,
    sensor: str = "truth",
    perception: PerceptionConfig | None = None,
    perception_seed: int | None = None,
) -> ExperimentResult:
    """Run E^V (Eq. 6.18): settle, check P_pre, transfer TM → TU, and back if y1 = 1; or
    the legs of an operation (`ExperimentSpec.leg`, module docstring).

    Never raises for a simulation problem: the result's status says what happened
    ('ok', 'invalid', 'unstable', 'error'). With the scene's implausible-event guard on
    (`PhysicsConfig.guard`) and a retry factor set, a run marked 'unstable' is run once more
    at the timestep times that factor (its result says so in `message`); a run in a given
    `system` is not re-run (the caller owns that system).

    Args:
        spec: The experiment.
        tu_hal: The transfer unit's HAL; None uses the simulated unit directly. The CPS
            passes an OPC UA HAL here that reaches the same simulated unit through its
            server, which must give the same record.
        system: A compiled system to run in instead of the one `spec.object_ref` and
            `spec.scene` describe (an emulated plant's hidden object and scene); the
            result's object id is then `spec.object_ref`.
        sensor: 'truth' (default) or 'perception': the controller sees the object through
            the TM's simulated depth camera (`transfertwin.perception.open_sensor`: scan,
            aim at the detection nearest to the conveyor's position, then one rendered and
            detected frame per sample with the camera following the object). Not part of
            the spec, so plans, hashes and stored results are those of ground truth.
        perception: Camera and pipeline of the perception sensor (default
            `PerceptionConfig()`).
        perception_seed: Seed of the camera's noise and RANSAC draws; None uses
            `spec.seed`.
    """
    if sensor not in SENSORS:
        raise InputError(f"sensor must be one of {', '.join(SENSORS)}, got {sensor!r}")
    if sensor == "perception" and spec.leg != "round-trip":
        raise InputError(
            "the perception sensor follows an object put down on the module: "
            f"leg 'round-trip' only, got {spec.leg!r}"
        )
    own_system = system is None
    if system is None:
        stamp = _stamp(spec.object_ref)  # one look at the file for system and id
        system = _system_for(spec.object_ref, spec.units, spec.scene, stamp)
        object_id = _object(spec.object_ref, spec.units, stamp).object_id
    else:
        object_id = spec.object_ref
    seeing = _Seeing(sensor, perception, perception_seed)
    result = _run(spec, system, object_id, tu_hal, seeing)
    physics = spec.scene.physics
    factor = physics.guard_retry_timestep_factor
    retry_ok = own_system and tu_hal is None  # a given system or HAL is the caller's
    if result.status == "unstable" and physics.guard and factor is not None and retry_ok:
        finer = physics.timestep_s * factor
        scene = spec.scene.with_overrides(**{
            "physics.timestep_s": finer, "physics.guard_retry_timestep_factor": None,
        })  # fmt: skip
        again = dataclasses.replace(spec, scene=scene)
        retry = _run(again, system_for(spec.object_ref, spec.units, scene), object_id, tu_hal,
                     seeing)  # fmt: skip
        note = f"re-run at {finer * 1000:g} ms after: {result.message}"
        result = dataclasses.replace(retry, message=f"{note}; {retry.message}".rstrip("; "))
    return result


@dataclass(frozen=True)
class _Seeing:
    """How the controller sees the object (`run_experiment`'s sensor arguments)."""

    sensor: str
    perception: PerceptionConfig | None
    seed: int | None


def _run(
    spec: ExperimentSpec,
    system: VirtualTransferSystem,
    object_id: str,
    tu_hal: UnitHAL | None,
    seeing: _Seeing,
) -> ExperimentResult:
    """One E^V in `system` (see `run_experiment`)."""
    base = {
        "face": spec.face,
        "conveyor": spec.conveyor,
        "theta_deg": spec.theta_deg,
        "run": spec.run,
        "seed": spec.seed,
    }
    base.update(zip(DOCKING_ERROR_COLUMNS, spec.docking_error.as_mm_deg(), strict=True))
    frames: list[Frame] = []
    (first, p1), second = _LEG_TRANSFERS[spec.leg]
    phase, offset = [p1], [0.0]

    def record() -> None:
        t_s = round(offset[0] + system.clock.now(), 6)  # the clock of t_end, to 1 µs
        frames.append(Frame(phase[0], t_s, _tuple(system.object_qpos())))

    tu = tu_hal if tu_hal is not None else system.tu
    vision = None  # the perception sensor, closed at the end
    try:
        _place_and_settle(system, spec)
        seen: ObjectSensor = system
        if seeing.sensor == "perception":
            from transfertwin.perception import open_sensor

            seen = vision = open_sensor(
                system, expected_xy=POSITIONS[spec.conveyor],
                theta_rad=math.radians(spec.theta_deg), config=seeing.perception,
                seed=spec.seed if seeing.seed is None else seeing.seed,
            )  # fmt: skip
        controller = scene_controller(
            spec.scene, system.tm, tu, seen, system.clock, record if spec.record else None
        )
        system.clock.start()
        s_pre = controller.state(spec.face, spec.conveyor)
        if not contains_state(_pre_set(spec.leg, controller.thresholds), s_pre):
            return ExperimentResult(
                object_id, **base, y1=None, y2=None, success=None, t_end_s=math.nan,
                status="invalid", message=_NOT_PRE[spec.leg],
                state_pre=_tuple(s_pre), frames=tuple(frames),
            )  # fmt: skip
        # a round trip runs the state's conveyor; a floor's module runs the belts the object
        # lies on (c from the observed box, Eq. 5.6), and so does the pick-up E^V
        there = controller.transfer(
            first, spec.face, spec.conveyor if spec.leg == "round-trip" else None
        )
        back: TransferRecord | None = None
        if there.y == 1 and second is not None:
            if spec.leg == "operation":  # docked at the destination with an error of its own
                system.dock(spec.delivery_docking_error or spec.docking_error)
            settle(system, spec.scene)
            phase[0], offset[0] = second[1], there.t_end_s
            back = controller.transfer(second[0], spec.face, None)
    except SimulationUnstable as exc:
        return ExperimentResult(
            object_id, **base, y1=None, y2=None, success=None, t_end_s=math.nan,
            status="unstable", message=str(exc), frames=tuple(frames),
        )  # fmt: skip
    except Exception as exc:  # failures are data: the batch goes on
        log.exception("experiment %s failed", spec)
        return ExperimentResult(
            object_id, **base, y1=None, y2=None, success=None, t_end_s=math.nan,
            status="error", message=f"{type(exc).__name__}: {exc}", frames=tuple(frames),
        )  # fmt: skip
    finally:
        if vision is not None:
            vision.close()
    y1 = there.y
    y2 = back.y if back is not None else None
    t2 = back.t_end_s if back is not None else math.nan
    message = "" if there.valid else "observed start state not in S_pre (Eq. 5.7)"
    if back is not None and not back.valid:
        message = (
            "object not in a return pre-transfer state after transfer 1"
            if spec.leg == "round-trip"
            else "object not in a delivery pre-transfer state after the pick-up"
        )
    return ExperimentResult(
        object_id, **base, y1=y1, y2=y2,
        success=int(y1 == 1 and (y2 == 1 or spec.leg == "pick-up")),
        t_end_s=there.t_end_s + (t2 if back is not None else 0.0), status="ok",
        t_end_1_s=there.t_end_s, t_end_2_s=t2, message=message,
        state_pre=_tuple(s_pre), state_end_1=_tuple(there.end_state),
        state_end_2=_tuple(back.end_state) if back is not None else (),
        frames=tuple(frames),
    )  # fmt: skip
