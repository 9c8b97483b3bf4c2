"""A study plan: objects × pre-transfer states × runs, each with its own seeds (Sec. 6.6).

The plan is a pure value. Its JSON form and hash identify it in the result store, so a
rerun resumes the same plan and a different plan on the same store is refused. Every
experiment's seeds derive from (master seed, object id, state index, run) through
`numpy.random.SeedSequence`, so a result does not depend on which worker ran it, in what
order, or whether the study was interrupted.
"""

from __future__ import annotations

import hashlib
import json
import zlib
from collections.abc import Container, Iterator
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from transfertwin._errors import InputError
from transfertwin.objects import builtin_ids, features_version, is_builtin_id
from transfertwin.ots import PreTransferState, experiment_states, filter_theta_step, state_index
from transfertwin.sim import SceneConfig
from transfertwin.study.docking import DockingErrorModel, docking_model_from_dict
from transfertwin.study.experiment._experiment import LEGS, ExperimentSpec
from transfertwin.study.experiment._profile import scene_to_dict

__all__ = [
    "PRESETS",
    "SAMPLING_MODES",
    "Preset",
    "StudyPlan",
    "check_theta_step",
    "delivery_docking_seed",
    "experiment_seeds",
    "parse_objects",
    "plan_parameters",
]

#: How a study chooses its runs: every planned run, or rounds chosen by
#: `transfertwin.study.adaptive.run_adaptive` (at most the planned runs per state).
SAMPLING_MODES = ("exhaustive", "adaptive")


@dataclass(frozen=True)
class Preset:
    """Defaults of a named study size."""

    objects: tuple[str, ...]
    theta_step: int
    runs: int


PRESETS: dict[str, Preset] = {
    # About five minutes on a 2-core machine: the four cores of the real calibration.
    "quick": Preset(("o1", "o18", "o23", "o32"), theta_step=30, runs=8),
    # The study's Full State Experiments: 37 × 924 × 50 = 1,709,400 (Eq. 6.20).
    "full": Preset(tuple(builtin_ids()), theta_step=1, runs=50),
}


def check_theta_step(step_deg: int, option: str = "--theta-step") -> int:
    """`step_deg` if it divides 360, so that the θ grid is even (every step the same size,
    including the one across ±180°); else an InputError naming `option` and the divisors."""
    if not 1 <= step_deg <= 360 or 360 % step_deg:
        divisors = ", ".join(str(d) for d in range(1, 361) if 360 % d == 0)
        raise InputError(
            f"{option} must divide 360 so that the θ grid is even ({divisors}), got {step_deg}"
        )
    return step_deg


def parse_objects(text: str) -> tuple[str, ...]:
    """'all', or a comma-separated list of built-in ids and mesh paths."""
    if text.strip() == "all":
        return tuple(builtin_ids())
    refs = tuple(part.strip() for part in text.split(",") if part.strip())
    if not refs:
        raise InputError("--objects is empty")
    known = set(builtin_ids())
    for ref in refs:
        if ref not in known and not Path(ref).is_file():
            raise InputError(
                f"unknown object {ref!r}: expected o1..o37, 'all' or a path to a mesh file"
            )
    if len(set(refs)) != len(refs):
        raise InputError("--objects lists an object twice")
    return refs


def experiment_seeds(master: int, object_id: str, state_idx: int, run: int) -> tuple[int, int]:
    """(experiment seed, docking-error seed) of one experiment, from the master seed."""
    words = _words(master, object_id, state_idx, run, 2)
    return int(words[0]), int(words[1])


def delivery_docking_seed(master: int, object_id: str, state_idx: int, run: int) -> int:
    """The seed of the delivery's docking error in an 'operation' experiment: the third word
    of the same seed sequence (the first two are `experiment_seeds`', unchanged)."""
    return int(_words(master, object_id, state_idx, run, 3)[2])


def _words(master: int, object_id: str, state_idx: int, run: int, n: int) -> np.ndarray:
    key = (zlib.crc32(object_id.encode()), state_idx, run)
    return np.random.SeedSequence(master, spawn_key=key).generate_state(n)


@dataclass(frozen=True)
class StudyPlan:
    """What a study runs. Experiments are ordered object by object, then state, then run.

    ``sampling`` is ``"exhaustive"`` (every run) or ``"adaptive"`` (``runs`` is then the most
    runs a state gets; ``sampling_options`` holds the adaptive settings as sorted
    ``(name, value)`` pairs). An exhaustive plan's description has no ``sampling`` entry, so
    its hash is the one it had before adaptive sampling existed.

    ``only_states`` (face, conveyor, θ) triples, when given, are the states run instead of
    every θ-step state (a small study, e.g. one the Experiment Manager runs on request); a
    plan without them has no ``states`` entry in its description, so its hash is unchanged.

    ``leg`` is what each experiment runs (`LEGS`: the study's 'round-trip', a floor's
    'pick-up' or its whole 'operation'); a round-trip plan has no ``leg`` entry in its
    description, so its hash is unchanged. An operation's delivery docks with an error of
    its own, drawn from `delivery_docking_seed`.
    """

    objects: tuple[str, ...]
    theta_step: int
    runs: int
    seed: int
    docking: DockingErrorModel
    scene: SceneConfig = field(default_factory=SceneConfig)
    profile_name: str = "default"
    units: str = "m"
    sampling: str = "exhaustive"
    sampling_options: tuple[tuple[str, object], ...] = ()
    only_states: tuple[tuple[str, str, int], ...] = ()
    leg: str = "round-trip"

    def __post_init__(self) -> None:
        if self.leg not in LEGS:
            raise InputError(f"--leg must be one of {', '.join(LEGS)}, got {self.leg!r}")
        if self.sampling not in SAMPLING_MODES:
            modes = ", ".join(SAMPLING_MODES)
            raise InputError(f"--sampling must be one of {modes}, got {self.sampling!r}")
        if self.sampling == "exhaustive" and self.sampling_options:
            raise InputError("adaptive sampling options given for an exhaustive study")
        object.__setattr__(self, "sampling_options", tuple(sorted(self.sampling_options)))
        if self.runs < 1:
            raise InputError(f"--runs must be >= 1, got {self.runs}")
        check_theta_step(self.theta_step)
        if self.seed < 0:
            raise InputError(f"--seed must be >= 0, got {self.seed}")
        if not self.objects:
            raise InputError("a study needs at least one object")
        only = tuple((str(f), str(c), int(t)) for f, c, t in self.only_states)
        for face, conveyor, theta in only:
            state_index(face, conveyor, theta)  # an experiment state (Eq. 6.7)
        if len(set(only)) != len(only):
            raise InputError("a study plan lists a pre-transfer state twice")
        object.__setattr__(self, "only_states", only)

    def states(self) -> tuple[PreTransferState, ...]:
        """The pre-transfer states run for every object (`only_states` in their order when
        given, else every state on the θ step)."""
        if self.only_states:
            by_key = {(s.face, s.conveyor, s.theta_deg): s for s in experiment_states()}
            return tuple(by_key[key] for key in self.only_states)
        return filter_theta_step(experiment_states(), self.theta_step)

    @property
    def n_experiments(self) -> int:
        """Number of planned experiments."""
        return len(self.objects) * len(self.states()) * self.runs

    def describe(self) -> dict[str, object]:
        """JSON-able description; identical plans have identical descriptions."""
        return (
            {
                "objects": list(self.objects),
                "theta_step": self.theta_step,
                "runs": self.runs,
                "seed": self.seed,
                "docking": self.docking.describe(),
                "profile": self.profile_name,
                "units": self.units,
                "scene": scene_to_dict(self.scene),
                "core_features": features_version()
                if any(map(is_builtin_id, self.objects))
                else None,
            }
            | (
                {"sampling": {"mode": self.sampling, **dict(self.sampling_options)}}
                if self.sampling != "exhaustive"
                else {}
            )
            | self._describe_states()
            | ({"leg": self.leg} if self.leg != "round-trip" else {})
        )

    def _describe_states(self) -> dict[str, object]:
        return {"states": [list(k) for k in self.only_states]} if self.only_states else {}

    def to_json(self) -> str:
        """Canonical JSON of `describe()`."""
        return json.dumps(self.describe(), sort_keys=True, separators=(",", ":"))

    @property
    def plan_hash(self) -> str:
        """sha256 of the canonical JSON."""
        return hashlib.sha256(self.to_json().encode()).hexdigest()

    @classmethod
    def from_json(cls, text: str) -> StudyPlan:
        """Rebuild a plan from `to_json()` output."""
        from transfertwin.study.experiment._profile import scene_from_dict

        d = json.loads(text)
        sampling = dict(d.get("sampling", {"mode": "exhaustive"}))
        mode = str(sampling.pop("mode"))
        return cls(
            objects=tuple(d["objects"]),
            theta_step=int(d["theta_step"]),
            runs=int(d["runs"]),
            seed=int(d["seed"]),
            docking=docking_model_from_dict(d["docking"]),
            scene=scene_from_dict(d["scene"]),
            profile_name=str(d.get("profile", "default")),
            units=str(d.get("units", "m")),
            sampling=mode,
            sampling_options=tuple(sampling.items()),
            only_states=tuple(tuple(k) for k in d.get("states", ())),
            leg=str(d.get("leg", "round-trip")),
        )

    def keys(self, object_ids: dict[str, str]) -> Iterator[tuple[str, str, str, int, int]]:
        """Store keys (object_id, face, conveyor, theta_deg, run) in plan order; cheap."""
        for ref in self.objects:
            for s in self.states():
                for run in range(self.runs):
                    yield object_ids[ref], s.face, s.conveyor, s.theta_deg, run

    def specs(
        self, object_ids: dict[str, str], skip: Container[tuple] = frozenset()
    ) -> Iterator[tuple[tuple, ExperimentSpec]]:
        """(store key, spec) of every experiment not in `skip`, in plan order.

        Args:
            object_ids: Object reference → object id (the id used in result rows).
            skip: Keys to leave out (done already); their docking errors are not drawn.
        """
        for ref in self.objects:
            oid = object_ids[ref]
            for s in self.states():
                idx = state_index(s.face, s.conveyor, s.theta_deg)
                for run in range(self.runs):
                    if (oid, s.face, s.conveyor, s.theta_deg, run) in skip:
                        continue
                    exp_seed, dock_seed = experiment_seeds(self.seed, oid, idx, run)
                    delivery = None
                    if self.leg == "operation":
                        delivery = self.docking.sample(
                            delivery_docking_seed(self.seed, oid, idx, run)
                        )
                    spec = ExperimentSpec(
                        ref, s.face, s.conveyor, s.theta_deg,
                        docking_error=self.docking.sample(dock_seed),
                        scene=self.scene, run=run, seed=exp_seed, units=self.units,
                        leg=self.leg, delivery_docking_error=delivery,
                    )  # fmt: skip
                    yield (oid, s.face, s.conveyor, s.theta_deg, run), spec


def plan_parameters(plan_json: str) -> dict[str, object]:
    """A stored plan flattened to ``section.key`` entries (for reports' parameter tables).

    Plan fields become ``plan.*``, the scene's scalars ``scene.*`` and its physics, layout
    and placement settings ``physics.*``, ``layout.*`` and ``placement.*``.
    """
    plan = json.loads(plan_json)
    scene = plan.pop("scene", {})
    out = {f"plan.{k}": v for k, v in plan.items()}
    out.update({f"scene.{k}": v for k, v in scene.items() if not isinstance(v, dict)})
    for section in ("physics", "layout", "placement"):
        out.update({f"{section}.{k}": v for k, v in scene.get(section, {}).items()})
    return out
