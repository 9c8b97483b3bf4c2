"""`EmulatedPlant`: a "physical" transfer system with hidden ground truth.

A plant is drawn from a seed (`transfertwin.plant._truth`): per object hidden resting
features (a protrusion per face from a wider prior than the twin's), a centre-of-mass
offset and a mass factor; friction μ, gap, a belt-speed error, a height step and pitch of
the docked TU, placement noise; per-station docking errors from the real data's copula with
perturbed location and scale; and a small probability that a recorded outcome is flipped.

Its experiments E^P are simulations in its own hidden scene. The twin sees only what a real
plant's log shows: one row per experiment with the columns of the real calibration table
(`PLANT_COLUMNS`). The hidden parameters live in name-mangled slots; no method returns
them (`fingerprint` is a hash, for reproducibility checks); what scores a rehearsal
afterwards draws them again from the seed (`reveal_truth`). Same seed and same requests →
same rows, bit for bit, with any number of workers.
"""

from __future__ import annotations

import dataclasses
import functools
import hashlib
import math
import multiprocessing as mp
import zlib
from collections.abc import Callable, Mapping, Sequence
from concurrent.futures import ProcessPoolExecutor
from dataclasses import asdict, dataclass

import mujoco
import numpy as np

from transfertwin._errors import InputError
from transfertwin.objects import ProxySpec, builtin_ids, load_builtin, proxy_model
from transfertwin.ots import state_index
from transfertwin.plant._bullet import BulletTransferSystem
from transfertwin.plant._mismatch import (
    PLANT_KINDS,
    SAG_SEGMENTS,
    MismatchObject,
    MismatchScene,
    check_mismatch_off,
    draw_mismatch_object,
    draw_mismatch_scene,
    mismatched_hulls,
    mismatched_inertia,
    without_parts,
)
from transfertwin.plant._mismatch_spec import (
    JointedPart,
    add_jointed_parts,
    add_sagging_decks,
    jointed_parts,
    slat_name,
)
from transfertwin.plant._recording import PlantRecording, _CameraTrack
from transfertwin.plant._truth import (
    PLANT_TAG,
    DockingTruth,
    ObjectTruth,
    SceneTruth,
    draw_docking,
    draw_object,
    draw_scene,
    real_copula,
)
from transfertwin.sim import (
    OBJECT_JOINT,
    DockingError,
    GapAreaLayout,
    MujocoUnitHAL,
    SceneConfig,
    VirtualTransferSystem,
    gap_area_m2,
)
from transfertwin.study.experiment import ExperimentSpec, run_experiment

__all__ = ["PLANT_COLUMNS", "EmulatedPlant", "MassReading", "PlantRequest"]

#: Columns of a plant row: those of the real calibration table.
PLANT_COLUMNS = (
    "experiment_id", "transfer_unit", "object_id", "theta_deg", "face", "conveyor", "success",
    "dock_err_x_mm", "dock_err_y_mm", "dock_err_theta_deg", "gap_area_cm2",
)  # fmt: skip

#: A mismatch plant's structural differences of one object and of the scene.
_Mismatch = tuple[MismatchObject, MismatchScene]

#: Attempts per experiment when the plant's simulation does not give a valid outcome
#: (an invalid settled state or a diverged run): a real operator would place again.
_ATTEMPTS = 3


@dataclass(frozen=True)
class PlantRequest:
    """One experiment asked of the plant: an object and a pre-transfer state, and optionally
    the transfer unit (station) the transport module docks at (None: as the plant's
    schedule has it, the stations in their logged shares)."""

    object_id: str
    face: str
    conveyor: str
    theta_deg: int
    station: str | None = None

    def __post_init__(self) -> None:
        state_index(self.face, self.conveyor, self.theta_deg)  # an experiment state (Eq. 6.7)
        object.__setattr__(self, "face", self.face.strip().lower())
        object.__setattr__(self, "conveyor", self.conveyor.strip().lower())
        object.__setattr__(self, "theta_deg", int(self.theta_deg))


class _SlippingHAL(MujocoUnitHAL):
    """A unit whose belts run `scale` times the commanded speed (reports the command).
    A sagging belt's slats (`_mismatch_spec`) run with its deck."""

    def __init__(self, system: VirtualTransferSystem, unit: str, scale: float) -> None:
        super().__init__(system, unit)
        self._scale = scale
        self._commanded: dict[str, float] = {}
        model = system.model
        self._slats = {
            belt: [model.geom(slat_name(unit, belt, i)).id for i in range(1, SAG_SEGMENTS)]
            for belt in ("left", "right")
            if mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_GEOM, slat_name(unit, belt, 1)) >= 0
        }  # fmt: skip

    def set_belt_speed(self, belt: str, speed_m_s: float) -> None:
        super().set_belt_speed(belt, speed_m_s * self._scale)
        self._commanded[belt] = float(speed_m_s)
        if belt in self._slats:
            surface = self._system.model.geom_surfacevel
            surface[self._slats[belt]] = surface[self._belt_rows[belt][0][0]]

    def belt_speed(self, belt: str) -> float:
        return self._commanded.get(belt, 0.0)


class _RipplingHAL(_SlippingHAL):
    """A mismatch plant's unit: on top of the slip, each belt's speed ripples by
    ±`ripple` at its pulleys' revolution frequency (run-out), and the right belt runs
    `1 + skew` times the left. Refreshed after every controller wait."""

    def __init__(self, system: VirtualTransferSystem, unit: str, scale: float, ripple: float,
                 phase: float, skew: float) -> None:  # fmt: skip
        super().__init__(system, unit, scale)
        self._ripple, self._phase, self._skew = ripple, phase, skew
        system.step_listeners.append(self._refresh)

    def _actual(self, belt: str, speed_m_s: float) -> float:
        v = speed_m_s * (1.0 + self._skew if belt == "right" else 1.0)
        t = float(self._system.data.time)
        return v * (1.0 + self._ripple * math.sin(abs(v) * self._scale / self._r * t
                                                  + self._phase))  # fmt: skip

    def set_belt_speed(self, belt: str, speed_m_s: float) -> None:
        super().set_belt_speed(belt, self._actual(belt, speed_m_s))
        self._commanded[belt] = float(speed_m_s)

    def _refresh(self) -> None:
        for belt, v in self._commanded.items():
            if v:
                _SlippingHAL.set_belt_speed(self, belt, self._actual(belt, v))
                self._commanded[belt] = v


class _PlantSystem(VirtualTransferSystem):
    """The plant's compiled system: hidden object, mass and belt-speed error (the TU's
    height step and pitch are scene settings, see `_scene_config`); with `mismatch` the
    structural differences of `transfertwin.plant._mismatch` on top."""

    def __init__(self, obj: ObjectTruth, scene: SceneTruth, cfg: SceneConfig,
                 mismatch: _Mismatch | None = None) -> None:  # fmt: skip
        model, mass_kg, com, inertia = _hidden_body(obj)
        hulls, features = model.hulls, model.feature_hulls
        self._parts: tuple[JointedPart, ...] = ()
        self._sag: tuple[tuple[float, float, float], ...] = ()
        if mismatch is not None:
            hulls, features = mismatched_hulls(hulls, features, mismatch[0])
            com = com + np.asarray(mismatch[0].com_shift_m)
            inertia = mismatched_inertia(inertia, mismatch[0])
            self._parts = jointed_parts(mismatch[0], hulls, len(model.hulls),
                                        model.feature_hulls)  # fmt: skip
            self._sag = mismatch[1].sag
        super().__init__(hulls, mass_kg, com, inertia, cfg, feature_hulls=features)
        # Every joint but the object's free one (jointed parts, slats): set at rest on placing.
        m = self.model
        free = m.joint(OBJECT_JOINT).id
        rest = [(j, int(m.jnt_type[j])) for j in range(m.njnt) if j != free]
        self._rest_q = [int(m.jnt_qposadr[j]) + i for j, t in rest for i in range(_QSIZE[t])]
        self._rest_v = [int(m.jnt_dofadr[j]) + i for j, t in rest for i in range(_VSIZE[t])]
        if mismatch is None:
            self.tm = _SlippingHAL(self, "tm", scene.belt_speed_scale)
            self.tu = _SlippingHAL(self, "tu", scene.belt_speed_scale)
            return
        ms = mismatch[1]
        self.tm, self.tu = (
            _RipplingHAL(self, unit, scene.belt_speed_scale, ms.ripple, ms.ripple_phase[k],
                         ms.right_belt_skew[k])
            for k, unit in enumerate(("tm", "tu"))
        )  # fmt: skip

    def _spec(self, hulls: tuple[np.ndarray, ...], mass_kg: float, com_m: np.ndarray,
              inertia_kg_m2: np.ndarray, cfg: SceneConfig,
              feature_hulls: int) -> mujoco.MjSpec:  # fmt: skip
        """The scene's spec with the mismatch's jointed parts and sagging decks."""
        spec = super()._spec(hulls, mass_kg, com_m, inertia_kg_m2, cfg, feature_hulls)
        if self._parts:
            add_jointed_parts(spec, self._parts)
        if self._sag:
            add_sagging_decks(spec, self._sag)
        return spec

    def place(self, face: str, theta_rad: float, x_m: float, y_m: float) -> None:
        """`VirtualTransferSystem.place`, with every jointed part and slat at rest (its
        spring's rest position, still)."""
        if self._rest_q:
            self.data.qpos[self._rest_q] = self.model.qpos_spring[self._rest_q]
            self.data.qvel[self._rest_v] = 0.0
        super().place(face, theta_rad, x_m, y_m)


#: Position and velocity coordinates per MuJoCo joint type (free, ball, slide, hinge).
_QSIZE = {0: 7, 1: 4, 2: 1, 3: 1}
_VSIZE = {0: 6, 1: 3, 2: 1, 3: 1}


def _object_model(obj: ObjectTruth):
    base = load_builtin(obj.object_id, features=False)
    return proxy_model(base, ProxySpec(obj.object_id, obj.object_id, obj.protrusions))


def _hidden_body(obj: ObjectTruth):
    """The plant object's model and its hidden mass properties in F_O, as every engine
    takes them: (model, mass (kg), centre of mass (m), inertia about it (kg·m²))."""
    model = _object_model(obj)
    mass = model.mass
    com = np.asarray(mass.com_m) + np.asarray(obj.com_offset_m)
    inertia = np.asarray(mass.inertia_kg_m2) * obj.mass_scale
    return model, mass.mass_kg * obj.mass_scale, com, inertia


def _scene_config(scene: SceneTruth, obj: ObjectTruth, refine: int = 0,
                  mismatch: MismatchScene | None = None) -> SceneConfig:  # fmt: skip
    """The plant's scene for one object. Its physics is trusted only where it is plausible:
    the guard is on, and a run it marks 'unstable' is run again at half, then a quarter of
    the timestep (`refine`). The plant stands in for reality, so it takes none of the
    twin's contact shortcuts: every hull of the object, multi-CCD on. A mismatch plant
    (`mismatch`) contacts through another solver and contact model (module
    `transfertwin.plant._mismatch`)."""
    physics = SceneConfig().physics
    extra = {} if mismatch is None or not mismatch.contact else {
        "physics.solver": "PGS", "physics.cone": "pyramidal", "physics.condim": 4,
        "physics.impratio": mismatch.impratio,
        "physics.solimp": (0.9, 0.95, mismatch.solimp_width_m, 0.5, 2.0),
    }  # fmt: skip
    return SceneConfig().with_overrides(**extra, **{
        "physics.multiccd": True,
        "physics.max_hulls": None,
        "physics.feature_solref": obj.feature_solref,
        "physics.guard": True,
        "physics.guard_retry_timestep_factor": None,
        "physics.timestep_s": physics.timestep_s / 2**refine,
        "mu": scene.mu,
        "gap_m": scene.gap_m,
        "layout.tu_height_offset_m": scene.step_z_m,
        "layout.tu_pitch_deg": math.degrees(scene.pitch_rad),
        "placement.sigma_xy_m": scene.sigma_xy_m,
        "placement.sigma_theta_deg": scene.sigma_theta_deg,
    })  # fmt: skip


@dataclass(frozen=True)
class MassReading:
    """What weighing and balancing a plant object shows: its mass (a scale, 1 g resolution,
    0.2 % error) and its centre of mass in F_O (three knife-edge balances, about 1 mm error
    per axis). A measurement, not the hidden value: the twin's mass counter-measure."""

    object_id: str
    mass_kg: float
    com_m: tuple[float, float, float]


@dataclass(frozen=True)
class _Job:
    """Everything one plant experiment needs (sent to a worker process)."""

    experiment_id: int
    request: PlantRequest
    obj: ObjectTruth
    scene: SceneTruth
    station: str
    error_mm_deg: tuple[float, float, float]
    seeds: tuple[int, ...]
    flip_u: float
    mismatch: _Mismatch | None = None
    engine: str = "mujoco"


#: Compiled plant systems of either engine, by ('mujoco' | 'bullet', object, scene, refine,
#: mismatch); a few at a time (a worker runs one object's jobs in a row).
_SYSTEMS: dict[tuple[object, ...], _PlantSystem | BulletTransferSystem] = {}

#: Timestep halvings tried when the plant's guard marks a run implausible.
_REFINE = 2


def _fresh_system(obj: ObjectTruth, scene: SceneTruth, refine: int = 0,
                  mismatch: _Mismatch | None = None) -> _PlantSystem:  # fmt: skip
    """A newly compiled plant system (not shared with the cache)."""
    ms = None if mismatch is None else mismatch[1]
    return _PlantSystem(obj, scene, _scene_config(scene, obj, refine, ms), mismatch)


def _fresh_bullet_system(obj: ObjectTruth, scene: SceneTruth,
                         refine: int = 0) -> BulletTransferSystem:  # fmt: skip
    """The in-class plant's system of `obj` in PyBullet (kind 'bullet'), newly built: the
    same hidden object (hulls, mass, centre of mass, inertia), scene (μ, gap, TU height
    step and pitch, belt-speed error, placement noise) and guard as `_fresh_system`'s."""
    model, mass_kg, com, inertia = _hidden_body(obj)
    return BulletTransferSystem(model.hulls, mass_kg, com, inertia,
                                _scene_config(scene, obj, refine), scene.belt_speed_scale)


def _cached(key: tuple[object, ...], make: Callable[[], object]):
    if key not in _SYSTEMS:
        if len(_SYSTEMS) >= 4:
            _SYSTEMS.clear()
        _SYSTEMS[key] = make()
    return _SYSTEMS[key]


def _system(obj: ObjectTruth, scene: SceneTruth, refine: int = 0,
            mismatch: _Mismatch | None = None) -> _PlantSystem:  # fmt: skip
    return _cached(("mujoco", obj, scene, refine, mismatch),
                   lambda: _fresh_system(obj, scene, refine, mismatch))  # fmt: skip


def _bullet_system(obj: ObjectTruth, scene: SceneTruth, refine: int = 0,
                   mismatch: _Mismatch | None = None) -> BulletTransferSystem:  # fmt: skip
    """`_fresh_bullet_system`, cached with `_system`'s."""
    assert mismatch is None, "the Bullet plant is the in-class plant in another engine"
    return _cached(("bullet", obj, scene, refine, None),
                   lambda: _fresh_bullet_system(obj, scene, refine))  # fmt: skip


@functools.lru_cache(maxsize=64)
def _mismatch_object(seed: int, object_id: str) -> MismatchObject:
    model = _object_model(draw_object(seed, object_id))
    return draw_mismatch_object(seed, object_id, model.hulls,
                                len(model.hulls) - model.feature_hulls)  # fmt: skip


def _run_job(
    job: _Job, systems: Callable[..., VirtualTransferSystem] | None = None
) -> tuple[dict[str, object], float]:
    """One E^P: simulate in the hidden scene (at finer steps after an implausible event,
    placing again if needed), record, maybe flip. `systems` hands out the plant system of
    each run (None: the job's engine's cache, `_system` or `_bullet_system`; or a camera's
    recording ones)."""
    if systems is None:
        systems = _bullet_system if job.engine == "bullet" else _system
    req = job.request
    error = DockingError.from_mm_deg(*job.error_mm_deg)
    success, t_end = 0, math.nan
    for seed in job.seeds:
        for refine in range(_REFINE + 1):
            ms = None if job.mismatch is None else job.mismatch[1]
            spec = ExperimentSpec(req.object_id, req.face, req.conveyor, req.theta_deg,
                                  docking_error=error,
                                  scene=_scene_config(job.scene, job.obj, refine, ms),
                                  seed=seed)  # fmt: skip
            result = run_experiment(spec, system=systems(job.obj, job.scene, refine,
                                                         job.mismatch))  # fmt: skip
            if result.status != "unstable":
                break
        if result.status == "ok":
            success, t_end = int(result.success or 0), float(result.t_end_s)
            break
    if job.flip_u < job.scene.flip_p:
        success = 1 - success
    gap = gap_area_m2(GapAreaLayout.fitted(), error, req.conveyor) * 1e4
    x, y, t = job.error_mm_deg
    return {
        "experiment_id": job.experiment_id, "transfer_unit": job.station,
        "object_id": req.object_id, "theta_deg": req.theta_deg, "face": req.face,
        "conveyor": req.conveyor, "success": success, "dock_err_x_mm": x, "dock_err_y_mm": y,
        "dock_err_theta_deg": t, "gap_area_cm2": round(gap, 2),
    }, t_end  # fmt: skip


class EmulatedPlant:
    """A transfer system with hidden ground truth, drawn from `seed`.

    Only `seed`, `kind`, `stations`, `experiments_run`, `fingerprint`, `run`, `operate`,
    `weigh` (a noisy measurement, like a scale's) and `observe` (a camera's recording of an
    experiment) are public; the hidden parameters cannot be read through them.

    Args:
        seed: Plant seed (non-negative integer): draws every hidden parameter.
        kind: 'in-class' (default): a plant of the twin's own model class with hidden
            values; 'mismatch': the same plant with structural differences the twin cannot
            represent (`transfertwin.plant._mismatch`); 'bullet': the in-class plant of the
            same seed (the same hidden objects, scene, docking errors and outcome flips)
            simulated in PyBullet instead of MuJoCo (`transfertwin.plant._bullet`), the
            engine being the structural difference. A kind, not an engine argument: the
            plant a rehearsal runs against is one named thing, and the mismatch's parts
            are MuJoCo models. A 'bullet' plant cannot be `observe`d (the recordings
            replay in MuJoCo).
    """

    __slots__ = ("__docking", "__kind", "__mismatch", "__next_id", "__off", "__scene", "__seed")

    def __init__(self, seed: int, kind: str = "in-class", *,
                 mismatch_off: tuple[str, ...] = ()) -> None:  # fmt: skip
        if isinstance(seed, bool) or not isinstance(seed, int) or seed < 0:
            raise InputError(f"--plant-seed must be a non-negative integer, got {seed!r}")
        if kind not in PLANT_KINDS:
            raise InputError(f"--plant-kind must be one of {', '.join(PLANT_KINDS)}, got {kind!r}")
        self.__off = check_mismatch_off(mismatch_off, kind)
        self.__seed = seed
        self.__kind = kind
        self.__scene: SceneTruth = draw_scene(seed)
        self.__docking: DockingTruth = draw_docking(seed)
        self.__mismatch: MismatchScene | None = (
            draw_mismatch_scene(seed) if kind == "mismatch" else None
        )
        self.__next_id = 0

    def __repr__(self) -> str:
        if self.__kind == "in-class":
            return f"EmulatedPlant(seed={self.__seed})"
        off = f", mismatch_off={tuple(sorted(self.__off))!r}" if self.__off else ""
        return f"EmulatedPlant(seed={self.__seed}, kind={self.__kind!r}{off})"

    @property
    def kind(self) -> str:
        """'in-class', 'mismatch' or 'bullet' (a setting, not a hidden value)."""
        return self.__kind

    def __reduce__(self) -> None:  # type: ignore[override]
        raise TypeError("an EmulatedPlant cannot be pickled (its parameters are hidden)")

    @property
    def seed(self) -> int:
        """The plant seed."""
        return self.__seed

    @property
    def stations(self) -> tuple[str, ...]:
        """Names of the plant's transfer units (as a real plant's log shows them)."""
        return self.__docking.stations

    @property
    def experiments_run(self) -> int:
        """Experiments run so far (the next experiment id)."""
        return self.__next_id

    def fingerprint(self, object_ids: Sequence[str] = ()) -> str:
        """SHA-256 of the hidden parameters (scene, docking, and the given objects): equal
        for equal plants, and reveals nothing of them."""
        parts = [asdict(self.__scene), asdict(self.__docking)]
        parts += [asdict(draw_object(self.__seed, o)) for o in object_ids]
        if self.__mismatch is not None:
            parts += [asdict(self.__mismatch), sorted(self.__off)]
            parts += [asdict(self.__mismatch_of(o)[0]) for o in object_ids]
        if self.__kind == "bullet":
            parts.append("engine: pybullet")
        return hashlib.sha256(repr(parts).encode()).hexdigest()

    def __mismatch_of(self, object_id: str) -> _Mismatch:
        assert self.__mismatch is not None
        return without_parts(_mismatch_object(self.__seed, object_id), self.__mismatch,
                             self.__off)  # fmt: skip

    def weigh(self, object_id: str) -> MassReading:
        """Weigh and balance plant object `object_id` (the same reading every time).

        A scale (0.2 % error) and knife-edge balances (about 1 mm per axis) read the
        object's real mass and centre of mass. On a mismatch plant that centre includes the
        mismatch's centre-of-mass shift (part 'mass'), read with the same noise: the twin
        is handed that shift as a measurement, so of the mass part only the per-axis
        inertia scaling stays hidden from a twin that weighs.
        """
        if object_id not in set(builtin_ids()):
            raise InputError(f"the plant has no object {object_id} (it holds o1..o37)")
        obj = draw_object(self.__seed, object_id)
        mass = _object_model(obj).mass
        rng = np.random.default_rng([PLANT_TAG, self.__seed, 5, zlib.crc32(object_id.encode())])
        kg = mass.mass_kg * obj.mass_scale * (1 + rng.normal(0.0, 0.002))
        com = np.asarray(mass.com_m) + np.asarray(obj.com_offset_m) + rng.normal(0, 0.001, 3)
        if self.__mismatch is not None:
            com = com + np.asarray(self.__mismatch_of(object_id)[0].com_shift_m)
        return MassReading(object_id, round(float(kg), 3), tuple(round(float(v), 4) for v in com))  # type: ignore[arg-type]

    def _jobs(self, requests: Sequence[PlantRequest]) -> list[_Job]:
        known = set(builtin_ids())
        bad = sorted({r.object_id for r in requests} - known)
        if bad:
            raise InputError(f"the plant has no object {', '.join(bad)} (it holds o1..o37)")
        jobs = []
        for req in requests:
            eid = self.__next_id
            self.__next_id += 1
            jobs.append(self.__job(eid, req))
        return jobs

    def __job(self, eid: int, req: PlantRequest) -> _Job:
        """Experiment `eid` for `req`: its draws follow from the plant seed and `eid`."""
        copula, dock = real_copula(), self.__docking
        ss = np.random.SeedSequence([PLANT_TAG, self.__seed, 4, eid])
        words = [int(w) for w in ss.generate_state(2 + _ATTEMPTS)]
        if req.station is None:
            raw, units = copula.sample_with_units(1, words[0])
        elif req.station in dock.stations:
            raw, units = copula.by_unit[req.station].sample_n(1, words[0]), (req.station,)
        else:
            raise InputError(f"the plant has no station {req.station!r} "
                             f"({', '.join(dock.stations)})")  # fmt: skip
        k = dock.stations.index(units[0])
        err = np.asarray(dock.shift[k]) + np.asarray(dock.scale[k]) * raw[0]
        err = np.clip(err, [-150.0, -150.0, -25.0], [150.0, 150.0, 25.0])
        flip_u = float(np.random.default_rng(words[1]).random())
        mismatch = None
        if self.__mismatch is not None:
            mismatch = self.__mismatch_of(req.object_id)
        return _Job(
            eid, req, draw_object(self.__seed, req.object_id), self.__scene, units[0],
            tuple(round(float(v), 2) for v in err), tuple(words[2:]), flip_u, mismatch,
            "bullet" if self.__kind == "bullet" else "mujoco",
        )  # fmt: skip

    def observe(self, row: Mapping[str, object]) -> PlantRecording:
        """Run again the experiment that made `row` (a row of this plant's `run` or
        `operate`, as returned or as read back from a CSV) and record it as a camera over
        the plant and its controller would have (`PlantRecording`: the object's pose at a
        camera's resolution, the barriers, the commanded belt speeds, the controller's clock
        starts and the logged row; no hidden parameter).

        The experiment is the one of the row's ``experiment_id`` (its draws follow from the
        plant seed and that id), for the row's object and state, with the transfer unit as
        the plant's schedule drew it or as the request named it. Does not count as an
        experiment (`experiments_run` is unchanged).

        Raises:
            InputError: The row lacks a column or does not come from this plant: its
                transfer unit, docking error or outcome differ from this plant's
                experiment of that id (another plant seed; another kind draws the same
                unit and error, and shows only where the outcome differs). Or the plant
                is a 'bullet' one: its camera recordings are not supported.
        """
        if self.__kind == "bullet":
            raise InputError("a 'bullet' plant cannot be observed: its experiments run in "
                             "PyBullet, the camera recordings and replays in MuJoCo")  # fmt: skip
        try:
            eid = int(str(row["experiment_id"]))
            req = PlantRequest(str(row["object_id"]), str(row["face"]), str(row["conveyor"]),
                               int(str(row["theta_deg"])))  # fmt: skip
            station = str(row["transfer_unit"])
            error = tuple(float(str(row[c])) for c in ("dock_err_x_mm", "dock_err_y_mm",
                                                        "dock_err_theta_deg"))  # fmt: skip
            logged = int(str(row["success"]))
        except KeyError as exc:
            raise InputError(f"a plant row needs the column {exc.args[0]!r} "
                             f"({', '.join(PLANT_COLUMNS)})") from None  # fmt: skip
        except ValueError as exc:
            raise InputError(f"not a plant row ({exc})") from None
        if eid < 0 or req.object_id not in set(builtin_ids()):
            raise InputError(f"not a plant row: experiment {eid}, object {req.object_id}")
        other = (f"experiment {eid} was not made by this plant (another plant seed or "
                 "kind?)")  # fmt: skip
        if station not in self.__docking.stations:
            raise InputError(f"{other}: it has no transfer unit {station!r}")
        job = next((j for j in (self.__job(eid, req),
                                self.__job(eid, dataclasses.replace(req, station=station)))
                    if j.station == station and j.error_mm_deg == error), None)  # fmt: skip
        if job is None:
            raise InputError(f"{other}: its transfer unit and docking error differ")
        track = _CameraTrack(_fresh_system)
        out, t_end = _run_job(job, systems=track.systems)
        if int(out["success"]) != logged:
            raise InputError(f"{other}: its logged outcome differs")
        return track.recording(out, t_end)

    def run(
        self,
        requests: Sequence[PlantRequest],
        *,
        workers: int = 1,
        on_progress: Callable[[int, int], None] | None = None,
    ) -> list[dict[str, object]]:
        """Run experiments E^P; one row per request, in request order (`PLANT_COLUMNS`).

        Experiment ids continue from earlier calls, and each experiment's random draws
        (station, docking error, placement, outcome noise) follow from the plant seed and
        its id, so the same sequence of calls gives the same rows.
        """
        return [row for row, _ in self._run(requests, workers, on_progress)]

    def operate(
        self,
        requests: Sequence[PlantRequest],
        *,
        workers: int = 1,
        on_progress: Callable[[int, int], None] | None = None,
    ) -> list[dict[str, object]]:
        """Run requests as operations: `run`'s rows plus ``transfer_time_s``, the time the
        transfer there and back took as the plant's clock shows it (NaN when the object
        never reached a valid pre-transfer state). Same ids and draws as `run`."""
        return [
            {**row, "transfer_time_s": t} for row, t in self._run(requests, workers, on_progress)
        ]

    def _run(
        self,
        requests: Sequence[PlantRequest],
        workers: int,
        on_progress: Callable[[int, int], None] | None,
    ) -> list[tuple[dict[str, object], float]]:
        if workers < 1:
            raise InputError(f"workers must be at least 1, got {workers}")
        jobs = self._jobs(list(requests))
        report = on_progress or (lambda done, total: None)
        report(0, len(jobs))
        out: list[tuple[dict[str, object], float]] = []
        if workers == 1 or len(jobs) <= 1:
            for job in jobs:
                out.append(_run_job(job))
                report(len(out), len(jobs))
            return out
        ctx = mp.get_context("spawn")
        with ProcessPoolExecutor(min(workers, len(jobs)), mp_context=ctx) as pool:
            for item in pool.map(_run_job, jobs):
                out.append(item)
                report(len(out), len(jobs))
        return out
