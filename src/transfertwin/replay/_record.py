"""Record one virtual experiment E^V as it runs: every clock wait's poses and signals.

`record_experiment(spec)` runs `transfertwin.study.experiment.run_experiment` as a study or
`transfertwin transfer` does (the same spec in a system compiled the same way, so the same
bits: the result is returned with the recording and can be compared with a stored row), with
the system's clock swapped for a `TrackingClock` (a `SimClock` that, after each wait,
lets a track note what it needs): here the simulation time, the object's free-joint
pose, the four light barriers, the four belt speeds and the object readout (Eq. 5.4
without f, c, t). Waiting and starting are `SimClock`'s own, so the physics is untouched.

The OTS phases (Eq. 4.11) are recovered from the clock starts and the controller's samples
(`ExperimentSpec.record` frames): each sample of a transfer is classified against the belt
sets of its direction (Eq. 5.7–5.10): pre-transfer (the start state), non-terminal, success
or failure.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import numpy as np

from transfertwin.objects import load_object
from transfertwin.ots import (
    NON_TERMINAL,
    BeltThresholds,
    Col,
    Conveyor,
    Face,
    TransferDirection,
    belt_sets,
    contains_state,
    conveyor_of,
    outcome_codes,
)
from transfertwin.sim import SceneConfig, TrackingClock, VirtualTransferSystem
from transfertwin.study.experiment import ExperimentResult, ExperimentSpec, run_experiment

__all__ = [
    "BARRIER_NAMES",
    "BELT_NAMES",
    "OTS_CODES",
    "Marker",
    "Replay",
    "compile_system",
    "record_experiment",
]

#: Light barriers in the order of `Replay.barriers`' columns.
BARRIER_NAMES: tuple[str, ...] = ("tm_near", "tm_far", "tu_near", "tu_far")
#: Belts in the order of `Replay.belts`' columns (surface speed, m/s, in the unit's x).
BELT_NAMES: tuple[str, ...] = ("tm_left", "tm_right", "tu_left", "tu_right")
#: Per-sample OTS codes (`Replay.ots`): no OTS formed (placing, settling), the pre-transfer
#: start state s(t0) ∈ S_pre, non-terminal S', success S+, failure S-, and a start state
#: outside S_pre (the transfer was not run).
OTS_CODES: dict[str, int] = {
    "none": -2, "pre": 2, "non_terminal": int(NON_TERMINAL), "success": 1, "failure": 0,
    "invalid": 3,
}  # fmt: skip


@dataclass(frozen=True)
class Marker:
    """A point of the time line: `t_s` on the replay's clock (simulation time since the
    object was placed), `kind` one of `OTS_CODES`' names, and a label in words."""

    t_s: float
    kind: str
    label: str


@dataclass(frozen=True)
class Replay:
    """One recorded E^V.

    Attributes:
        spec: The experiment as run (`record` on); for a plant experiment, the twin's
            setting of it (its nominal scene and the measured docking error), which draws it.
        result: Its result (the same as the study's or `transfer`'s for this spec); None
            for a plant experiment, whose outcome is the plant's logged row (`logged`).
        t_s: Simulation time of each sample since the object was placed, (n,).
        qpos: The object's free-joint pose at each sample, (n, 7): position (m) and
            quaternion (w, x, y, z) in F_T.
        barriers: Whether each light barrier (`BARRIER_NAMES`) is interrupted, (n, 4).
        belts: Commanded surface speed of each belt (`BELT_NAMES`), (n, 4), m/s.
        ots: OTS code of each sample (`OTS_CODES`), (n,).
        markers: The OTS transitions on the time line.
        tu_pose: The docked TU's (x, y, yaw) in F_T: the docking error made visible.
        nominal_tu_pose: Where the TU lies without a docking error.
        logged: A plant experiment's logged row (`transfertwin.plant.PLANT_COLUMNS` and
            ``transfer_time_s``); None for a virtual one.
    """

    spec: ExperimentSpec
    result: ExperimentResult | None
    t_s: np.ndarray
    qpos: np.ndarray
    barriers: np.ndarray
    belts: np.ndarray
    ots: np.ndarray
    markers: tuple[Marker, ...]
    tu_pose: tuple[float, float, float]
    nominal_tu_pose: tuple[float, float, float]
    logged: dict[str, object] | None = None

    @property
    def duration_s(self) -> float:
        """Time of the last sample."""
        return float(self.t_s[-1]) if len(self.t_s) else 0.0


class _Track:
    """What the recording clock saw; `segment` counts the clock starts so far."""

    def __init__(self) -> None:
        self.starts: list[float] = []
        self.rows: list[tuple[float, ...]] = []
        self.segment: list[int] = []

    def sample(self, system: VirtualTransferSystem) -> None:
        tm, tu = system.tm.barriers(), system.tu.barriers()
        row = (
            float(system.data.time),
            *system.object_qpos().tolist(),
            float(tm["near"]), float(tm["far"]), float(tu["near"]), float(tu["far"]),
            system.tm.belt_speed("left"), system.tm.belt_speed("right"),
            system.tu.belt_speed("left"), system.tu.belt_speed("right"),
            *system.observe().tolist(),
        )  # fmt: skip
        self.rows.append(row)
        self.segment.append(len(self.starts))


def compile_system(spec: ExperimentSpec, scene: SceneConfig | None = None) -> VirtualTransferSystem:
    """A freshly compiled system for `spec`'s object and scene (or `scene`), as
    `system_for` builds it but not shared: a replay never runs in a system that another
    thread (a live transfer of the console) may be stepping."""
    obj = load_object(spec.object_ref, units=spec.units)
    return VirtualTransferSystem(
        obj.hulls, obj.mass.mass_kg, obj.mass.com_m, obj.mass.inertia_kg_m2,
        spec.scene if scene is None else scene, feature_hulls=obj.feature_hulls,
    )  # fmt: skip


def _run(spec: ExperimentSpec, scene: SceneConfig) -> tuple[ExperimentResult, _Track, tuple]:
    system = compile_system(spec, scene)
    track = _Track()
    system.clock = TrackingClock(system, track)
    result = run_experiment(dataclasses.replace(spec, scene=scene), system=system)
    return result, track, tuple(float(v) for v in system.tu_pose)


def record_experiment(spec: ExperimentSpec) -> Replay:
    """Run `spec` (ground-truth sensor) and record it (see the module doc).

    As `run_experiment` does for a spec, a run marked 'unstable' with the scene's guard on
    is run once more at the finer timestep (and the replay shows that run)."""
    spec = dataclasses.replace(spec, record=True)
    result, track, tu_pose = _run(spec, spec.scene)
    physics = spec.scene.physics
    factor = physics.guard_retry_timestep_factor
    if result.status == "unstable" and physics.guard and factor is not None:
        finer = physics.timestep_s * factor
        scene = spec.scene.with_overrides(**{
            "physics.timestep_s": finer, "physics.guard_retry_timestep_factor": None,
        })  # fmt: skip
        note = f"re-run at {finer * 1000:g} ms after: {result.message}"
        retry, track, tu_pose = _run(spec, scene)
        result = dataclasses.replace(retry, message=f"{note}; {retry.message}".rstrip("; "))
    obj_id = load_object(spec.object_ref, units=spec.units).object_id
    result = dataclasses.replace(result, object_id=obj_id)
    if not track.rows:
        raise RuntimeError("the replay recorder saw no sample of the experiment")
    data = np.array(track.rows)
    segment = np.array(track.segment)
    ots, markers = _ots_phases(spec, result, data, segment, track.starts)
    return Replay(
        spec=spec, result=result, t_s=data[:, 0].copy(), qpos=data[:, 1:8].copy(),
        barriers=data[:, 8:12] > 0.5, belts=data[:, 12:16].copy(), ots=ots,
        markers=tuple(markers), tu_pose=tu_pose,
        nominal_tu_pose=(float(spec.scene.gap_m), 0.0, 0.0),
    )  # fmt: skip


_ARROW = {TransferDirection.TM_TO_TU: "TM → TU", TransferDirection.TU_TO_TM: "TU → TM"}


def _ots_phases(
    spec: ExperimentSpec,
    result: ExperimentResult,
    data: np.ndarray,
    segment: np.ndarray,
    starts: list[float],
) -> tuple[np.ndarray, list[Marker]]:
    """Per-sample OTS codes and the time line's markers.

    The clock starts at the check of S_pre (start 1), again when transfer 1 forms its OTS
    (start 2) and when transfer 2 does (start 3). After a start, the controller's samples
    of that transfer are the first n waits (n from the recorded frames: transfer 1 observes
    twice at t0, transfer 2 once, then once per wait).
    """
    codes = np.full(len(data), OTS_CODES["none"], dtype=np.int8)
    markers = [Marker(0.0, "none", "object placed; settling with the belts stopped")]
    there = sum(1 for f in result.frames if f.phase == "there")
    back = sum(1 for f in result.frames if f.phase == "back")
    thresholds = BeltThresholds(t_max=spec.scene.t_max_s)
    face = int(Face[spec.face.upper()])
    plan = [(2, TransferDirection.TM_TO_TU, max(0, there - 2), result.y1, result.t_end_1_s),
            (3, TransferDirection.TU_TO_TM, max(0, back - 1), result.y2, result.t_end_2_s)]
    if len(starts) >= 1 and result.status == "invalid":
        i = int(np.searchsorted(data[:, 0], starts[0], side="right")) - 1
        if i >= 0:
            codes[i] = OTS_CODES["invalid"]
        markers.append(Marker(starts[0], "invalid", "settled state not in S_pre: no transfer"))
    for start_no, direction, n, y, t_end in plan:
        if len(starts) < start_no or (y is None and n == 0):
            continue
        t0 = starts[start_no - 1]
        sets = belt_sets(direction, thresholds)
        first = int(np.searchsorted(segment, start_no))  # the first wait after this start
        before = first - 1  # the state the OTS was formed in
        if before >= 0:
            obs = data[before, 16:24]
            conveyor = (
                int(Conveyor[spec.conveyor.upper()])
                if direction is TransferDirection.TM_TO_TU
                else int(conveyor_of(obs[Col.Y], obs[Col.SY]))
            )
            s0 = np.array([*obs, face, conveyor, 0.0])
            ok = contains_state(sets.pre, s0)
            codes[before] = OTS_CODES["pre" if ok else "invalid"]
            word = "s(t0) ∈ S_pre: OTS formed" if ok else "s(t0) not in S_pre: not run"
            markers.append(Marker(t0, "pre" if ok else "invalid", f"{_ARROW[direction]}: {word}"))
        else:
            conveyor = int(Conveyor[spec.conveyor.upper()])
        rows = range(first, min(first + n, len(data)))
        for i in rows:
            s = np.array([*data[i, 16:24], face, conveyor, data[i, 0] - t0])
            codes[i] = int(outcome_codes(s, sets.success, sets.failure))
        if y is not None and len(rows):
            last = rows[-1]
            kind = "success" if y == 1 else "failure"
            note = "" if codes[last] == y else " (early timeout: carried to t_max)"
            codes[last] = OTS_CODES[kind]
            t_txt = "" if math.isnan(t_end) else f", t_end = {t_end:.2f} s"
            sign = "S+" if y == 1 else "S−"
            markers.append(Marker(float(data[last, 0]), kind,
                                  f"{_ARROW[direction]}: s(t_end) ∈ {sign}, {kind}{t_txt}{note}"))
    return codes, markers
