"""What one rehearsal is asked to do (`RehearsalConfig`, checked when it is made) and the
twin's counter-measures against its sim-to-real gap (`COUNTER_MEASURES`, `twin_scene`);
`config_record` is the configuration as ``rehearsal.json`` records it.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from dataclasses import asdict, dataclass, field

from transfertwin._errors import InputError
from transfertwin.objects import builtin_ids
from transfertwin.plant import MISMATCH_PARTS, PLANT_KINDS
from transfertwin.sim import SceneConfig

__all__ = [
    "COUNTER_MEASURES",
    "FULLSTATE_SAMPLINGS",
    "OBJECT_PRIORS",
    "TWIN_FEATURE_SOLREF",
    "RehearsalConfig",
    "config_record",
    "parse_ablations",
    "parse_object_list",
    "twin_scene",
]


#: The twin's counter-measures against the study's three causes of its sim-to-real gap:
#: measured mass (a scale and a balance, instead of uniform density), the implausible-event
#: guard (launches, energy jumps, deep penetration, NaN: the run is marked 'unstable' and
#: re-run once at half the timestep), compliant features (a proxy's protrusions yield).
COUNTER_MEASURES = ("mass", "stability", "compliance")


#: Contact time constant and damping ratio the twin gives a proxy's features when they are
#: marked compliant: nominal values of a soft part (the middle of the emulated plant's prior,
#: 30-80 ms and 0.5-1.0), not fitted.
TWIN_FEATURE_SOLREF = (0.05, 0.75)

#: What object calibration moves away from: the plain body of uniform density (the study's
#: family prior) or each face's shipped feature (what the uncalibrated twin simulates).
OBJECT_PRIORS = ("plain", "shipped")

#: How the full-state prediction spends its runs (`RehearsalConfig.fullstate_sampling`).
FULLSTATE_SAMPLINGS = ("exhaustive", "adaptive")


def parse_ablations(values: Sequence[str]) -> tuple[str, ...]:
    """``['mass', 'stability,compliance']`` → ('mass', 'stability', 'compliance')."""
    out: list[str] = []
    for value in values:
        for part in (p.strip().lower() for p in value.split(",")):
            if not part:
                continue
            if part not in COUNTER_MEASURES:
                known = ", ".join(COUNTER_MEASURES)
                raise InputError(f"--ablate: unknown counter-measure {part!r} (one of {known})")
            if part not in out:
                out.append(part)
    return tuple(out)


def twin_scene(base: SceneConfig, measures: Iterable[str]) -> SceneConfig:
    """The twin's scene with counter-measures on: 'stability' turns the implausible-event
    guard on (re-run at half the timestep), 'compliance' makes features compliant
    (`TWIN_FEATURE_SOLREF`). 'mass' changes the objects, not the scene."""
    measures = set(measures)
    changes: dict[str, object] = {}
    if "stability" in measures:
        changes["physics.guard"] = True
    if "compliance" in measures:
        changes["physics.feature_solref"] = TWIN_FEATURE_SOLREF
    return base.with_overrides(**changes) if changes else base


def parse_object_list(text: str) -> tuple[str, ...]:
    """``'o3,o7'`` → ('o3', 'o7'); built-in cores only (the plant holds o1..o37)."""
    ids = tuple(p.strip() for p in text.split(",") if p.strip())
    if not ids:
        raise InputError("--objects: name at least one object, e.g. o3,o7")
    known = set(builtin_ids())
    bad = [o for o in ids if o not in known]
    if bad:
        raise InputError(f"--objects: unknown object(s) {', '.join(bad)} (built-in o1..o37)")
    if len(set(ids)) != len(ids):
        raise InputError("--objects: an object is named twice")
    return ids


@dataclass(frozen=True)
class RehearsalConfig:
    """One rehearsal.

    Attributes:
        plant_seed: Seed of the emulated plant (draws its hidden parameters).
        objects: Built-in core ids.
        calibration_experiments: K plant experiments for calibration (and held-out scoring).
        runs: Replay repetitions R per row and candidate, and runs per state in the
            full-state prediction.
        validation_runs: Plant experiments (and virtual runs) per best/worst state.
        theta_step: θ grid of the full-state prediction (degrees, divides 360).
        holdout: Share of the K experiments held out for f05_before/f05_after (when
            `test_experiments` is 0).
        test_experiments: H extra plant experiments, run before the K calibration ones
            (same design, own random stream), used only to score f05_before/f05_after; all
            K experiments then calibrate. 0: the K experiments are split (`holdout`). With
            H > 0 every K of a curve is scored on the same H plant experiments.
        depths_mm: Candidate protrusion depths of the object calibration (0 is added).
        proxy_positions: Candidate protrusion positions along the object's x axis searched
            with the depths (fractions of its length, 0.5 the centre, which is added);
            (0.5,), the default: centred protrusions, depth only.
        tune_trials: TPE trials over μ and the gap (0: object calibration only).
        object_prior: What object calibration moves away from (`OBJECT_PRIORS`): 'plain'
            (the plain body; a fitted proxy replaces the core's shipped features) or
            'shipped' (each face's shipped feature, kept unless its rows say otherwise).
        min_face_rows: Training rows a face needs before object calibration searches its
            depth; a face with fewer keeps its prior (1: every face tried is searched).
        fullstate_sampling: How the full-state prediction spends its `runs` a state
            (`FULLSTATE_SAMPLINGS`): 'exhaustive' (every state alike, the study's) or
            'adaptive' (the same budget, spent on each object's leaders and challengers,
            as the floor's on-the-fly predictions).
        seed: Master seed of the twin's side (design, split, simulations).
        workers: Worker processes.
        scene: The twin's starting scene (profile), before counter-measures.
        ablate: Counter-measures (`COUNTER_MEASURES`) to switch off, one at a time, in
            extra twin variants that reuse the plant's calibration rows.
        operations: Orders per policy in the operational comparison (0: none), see
            `run_operations`.
        plant_kind: 'in-class' (a plant of the twin's model class with hidden values),
            'mismatch' (structural differences the twin cannot represent) or 'bullet' (the
            in-class plant simulated in PyBullet), see `transfertwin.plant.EmulatedPlant`.
        mismatch_off: Parts of the mismatch plant switched off (`MISMATCH_PARTS`; a
            rehearsal per ablated part, docs/fidelity.md); only with 'mismatch'.
        design: The calibration experiments' states (`DESIGNS`): 'random' (the study's)
            or 'space-filling' (a Latin hypercube over face and θ per object).
    """

    plant_seed: int
    objects: tuple[str, ...]
    calibration_experiments: int
    runs: int = 2
    validation_runs: int = 10
    theta_step: int = 90
    holdout: float = 0.3
    test_experiments: int = 0
    depths_mm: tuple[float, ...] = (8.0, 16.0, 24.0, 32.0)
    proxy_positions: tuple[float, ...] = (0.5,)
    tune_trials: int = 0
    object_prior: str = "plain"
    min_face_rows: int = 1
    fullstate_sampling: str = "exhaustive"
    seed: int = 0
    workers: int = 1
    scene: SceneConfig = field(default_factory=SceneConfig)
    ablate: tuple[str, ...] = ()
    operations: int = 0
    plant_kind: str = "in-class"
    mismatch_off: tuple[str, ...] = ()
    design: str = "random"

    def __post_init__(self) -> None:
        from transfertwin.rehearsal._design import DESIGNS

        if self.design not in DESIGNS:
            raise InputError(f"--design must be one of {', '.join(DESIGNS)}, got {self.design!r}")
        object.__setattr__(self, "ablate", parse_ablations(self.ablate))
        if self.plant_kind not in PLANT_KINDS:
            raise InputError(
                f"--plant-kind must be one of {', '.join(PLANT_KINDS)}, got {self.plant_kind!r}"
            )
        object.__setattr__(self, "mismatch_off", tuple(self.mismatch_off))
        bad = sorted(set(self.mismatch_off) - set(MISMATCH_PARTS))
        if bad or (self.mismatch_off and self.plant_kind != "mismatch"):
            raise InputError(
                f"--mismatch-off takes parts of the mismatch plant ({', '.join(MISMATCH_PARTS)}) "
                f"with --plant-kind mismatch, got {', '.join(self.mismatch_off)}"
            )
        if self.operations < 0:
            raise InputError("--operations must be >= 0")
        for name in ("plant_seed", "seed"):
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, int) or v < 0:
                raise InputError(f"--{name.replace('_', '-')} must be a non-negative integer")
        for name in ("calibration_experiments", "runs", "validation_runs", "workers"):
            if getattr(self, name) < 1:
                raise InputError(f"--{name.replace('_', '-')} must be at least 1")
        if self.tune_trials < 0:
            raise InputError("--tune-trials must be >= 0")
        if self.fullstate_sampling not in FULLSTATE_SAMPLINGS:
            raise InputError(f"fullstate sampling must be one of "
                             f"{', '.join(FULLSTATE_SAMPLINGS)}, got {self.fullstate_sampling!r}")
        if self.object_prior not in OBJECT_PRIORS:
            raise InputError(f"--object-prior must be one of {', '.join(OBJECT_PRIORS)}, "
                             f"got {self.object_prior!r}")  # fmt: skip
        if isinstance(self.min_face_rows, bool) or not isinstance(self.min_face_rows, int) \
                or self.min_face_rows < 1:  # fmt: skip
            raise InputError(f"--min-face-rows must be an integer >= 1, got {self.min_face_rows!r}")
        if not (0 < self.holdout < 1):
            raise InputError(f"--holdout must be in (0, 1), got {self.holdout}")
        if isinstance(self.test_experiments, bool) or self.test_experiments < 0:
            raise InputError("--test-experiments must be >= 0")
        n_test = round(self.calibration_experiments * self.holdout)
        if self.test_experiments and self.calibration_experiments < 2:
            raise InputError("--calibration-experiments must be at least 2")
        if not self.test_experiments and (n_test < 1 or self.calibration_experiments - n_test < 2):
            raise InputError(
                "--calibration-experiments too small for the hold-out split "
                f"({self.calibration_experiments} x {self.holdout})"
            )
        if not (1 <= self.theta_step <= 360 and 360 % self.theta_step == 0):
            raise InputError(f"--theta-step must divide 360, got {self.theta_step}")
        if not self.objects:
            raise InputError("--objects: name at least one object")
        if any(not (0 < d <= 100) for d in self.depths_mm):
            raise InputError("--depths-mm must be in (0, 100]")
        if not self.proxy_positions or any(
            not (0.0 <= x <= 1.0) for x in self.proxy_positions
        ):  # fmt: skip
            raise InputError("--proxy-positions must be fractions in 0..1")


def config_record(cfg: RehearsalConfig) -> dict[str, object]:
    """The configuration for ``rehearsal.json``: without the scene, and without the plant
    seed, which draws every hidden value of the plant (`rehearse` writes it to the
    owner-only ``plant.secret`` beside the record); `proxy_positions` only when positions
    were searched, so that a default rehearsal writes what it wrote before."""
    out = {k: v for k, v in asdict(cfg).items() if k not in ("scene", "plant_seed")}
    if set(cfg.proxy_positions) == {0.5}:
        del out["proxy_positions"]
    if cfg.plant_kind == "in-class":
        del out["plant_kind"]
    if not cfg.mismatch_off:
        del out["mismatch_off"]
    if cfg.design == "random":
        del out["design"]
    if cfg.object_prior == "plain":
        del out["object_prior"]
    if cfg.min_face_rows == 1:
        del out["min_face_rows"]
    if cfg.fullstate_sampling == "exhaustive":
        del out["fullstate_sampling"]
    return out
