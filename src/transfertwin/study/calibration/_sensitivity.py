"""Sensitivity of the replayed outcomes to candidate gap mechanisms.

Which unmeasured mechanism makes the twin fail where the real system fails? Every real row
(face, conveyor, θ, measured docking error) is replayed as in `calibrate`, under scenes that
differ from a base profile in one *factor* at a time (`one_at_a_time`), or along Morris
trajectories (`morris_screening`, SALib). All scenes share the replay seeds (common random
numbers), so a difference between levels is the factor's, not the placement noise's.

Per scene, the figures that tell a mechanism apart:

- success share over rows × runs, with its Clopper–Pearson 95 % interval;
- the share of failures that are **stuck at the gap** — the real failure mode: the failing
  transfer ended (timeout or stall) with the object's AABB centre within `GAP_ZONE_M` of the
  TM tip and its bottom not more than `FALL_DEPTH_M` below the belt surface (`outcome`);
- F0.5 against the real outcomes (mean over runs) and the AUC of the simulated failure
  share per row against real failure (0.5: the twin fails on the wrong rows);
- the *signature*: success share by face, conveyor and yaw band (|θ| folded onto 0–90°:
  0–30, 30–60, 60–90°), and per object and face, to compare with the real one.

A factor is a named scene setting with a range (`FACTORS`), or any float setting of
`SceneConfig` by its dotted name. Simulations run through `run_tagged` in one worker pool.
"""

from __future__ import annotations

import json
import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field

import numpy as np

from transfertwin._errors import InputError
from transfertwin.sim import SceneConfig
from transfertwin.study.calibration._metrics import ConfusionMatrix
from transfertwin.study.calibration._replay import check_real_rows, parse_object_map, replay_specs
from transfertwin.study.experiment import run_tagged
from transfertwin.study.fullstate import clopper_pearson

__all__ = [
    "FACTORS",
    "FALL_DEPTH_M",
    "GAP_ZONE_M",
    "YAW_BANDS",
    "Factor",
    "LevelResult",
    "MorrisResult",
    "SensitivityResult",
    "factor_levels",
    "morris_screening",
    "one_at_a_time",
    "outcome",
    "parse_factors",
    "scene_at",
    "signature",
    "yaw_band",
]

#: A failing transfer whose object ends with its AABB centre this close to the TM tip (x in
#: F_T, m) is stuck at the gap.
GAP_ZONE_M = 0.12
#: An object whose AABB bottom ends more than this below the belt surface (m) has fallen.
FALL_DEPTH_M = 0.03
#: Yaw bands (degrees of |θ| folded onto 0–90°): [lo, hi) except the last, which is closed.
YAW_BANDS: tuple[tuple[str, float, float], ...] = (
    ("0-30", 0.0, 30.0),
    ("30-60", 30.0, 60.0),
    ("60-90", 60.0, 90.0),
)
_FACES = ("front", "back")
_CONVEYORS = ("left", "both", "right")


@dataclass(frozen=True)
class Factor:
    """A scene setting varied over [low, high].

    Attributes:
        name: Name in tables and on the command line.
        key: `SceneConfig.with_overrides` key it sets (``physics.solref`` sets the time
            constant and keeps the base damping ratio).
        low, high: Range, in the factor's own unit.
        scale: Factor value × scale = setting value (e.g. 0.001 for mm → m).
        note: What the factor stands for.
    """

    name: str
    key: str
    low: float
    high: float
    scale: float = 1.0
    note: str = ""

    def to_dict(self) -> dict[str, object]:
        """JSON-ready description."""
        return {"name": self.name, "key": self.key, "low": self.low, "high": self.high,
                "scale": self.scale, "note": self.note}  # fmt: skip


#: The default candidate mechanisms and their ranges.
FACTORS: tuple[Factor, ...] = (
    Factor("tu_height_offset_m", "layout.tu_height_offset_m", -0.006, 0.006,
           note="TU belt surface step above the TM (unmeasured docking component)"),
    Factor("tu_pitch_deg", "layout.tu_pitch_deg", -3.0, 3.0,
           note="TU tilt about the gap line, + raises its far end"),
    Factor("tu_roll_deg", "layout.tu_roll_deg", -3.0, 3.0,
           note="TU tilt about its centre line, + raises its left belt"),
    Factor("pulley_radius_m", "layout.pulley_radius_m", 0.0125, 0.03,
           note="end pulley radius (study: not given)"),
    Factor("gap_mm", "gap_m", 6.0, 30.0, scale=0.001, note="nominal gap d_gap"),
    Factor("mu", "mu", 0.3, 0.8, note="belt friction mu_k"),
    Factor("solref_timeconst_s", "physics.solref", 0.01, 0.05,
           note="contact stiffness: solref time constant (>= 2 timesteps)"),
    Factor("feature_mu", "feature_mu", 0.2, 1.2,
           note="friction of a proxy's protrusions (no effect without proxies)"),
    Factor("com_offset_m", "com_offset_m", -0.03, 0.03,
           note="centre of mass shifted along the object axis"),
)  # fmt: skip
_BY_NAME = {f.name: f for f in FACTORS}


def scene_at(base: SceneConfig, factor: Factor, value: float) -> SceneConfig:
    """`base` with `factor` set to `value` (InputError if the scene rejects it)."""
    v = float(value) * factor.scale
    if factor.key == "physics.solref":
        return base.with_overrides(**{factor.key: (v, base.physics.solref[1])})
    return base.with_overrides(**{factor.key: v})


def _generic(name: str, base: SceneConfig) -> Factor:
    head, _, tail = name.partition(".")
    owner = getattr(base, head, None) if tail else base
    current = getattr(owner, tail or head, None) if owner is not None else None
    if isinstance(current, bool) or not isinstance(current, float):
        known = ", ".join(_BY_NAME)
        raise InputError(
            f"--params: {name!r} is neither a known factor ({known}) "
            "nor a numeric scene setting such as layout.belt_speed_m_s"
        )
    return Factor(name, name, current, current)


def parse_factors(text: str | None, base: SceneConfig) -> tuple[Factor, ...]:
    """``--params``: ``NAME=LO:HI,...`` (or a bare ``NAME`` for its default range); NAME is
    a factor of `FACTORS` or a float setting of `SceneConfig` by dotted name. None or ""
    gives `FACTORS`. Each range's ends are checked against the scene's own validation."""
    if not text or not text.strip():
        factors = list(FACTORS)
    else:
        factors = []
        for part in text.split(","):
            part = part.strip()
            if not part:
                continue
            name, sep, rng = part.partition("=")
            name = name.strip()
            factor = _BY_NAME.get(name) or _generic(name, base)
            if sep:
                lo, colon, hi = rng.partition(":")
                try:
                    low, high = float(lo), float(hi)
                except ValueError:
                    low = high = math.nan
                if not colon or not (math.isfinite(low) and math.isfinite(high)) or low >= high:
                    raise InputError(f"--params: {part!r} is not NAME=LO:HI with LO < HI")
                factor = Factor(factor.name, factor.key, low, high, factor.scale, factor.note)
            elif factor.low >= factor.high:
                raise InputError(f"--params: {name!r} has no default range; use {name}=LO:HI")
            factors.append(factor)
        if not factors:
            raise InputError("--params is empty")
        names = [f.name for f in factors]
        if len(set(names)) != len(names):
            raise InputError("--params names a factor twice")
    for factor in factors:
        for value in (factor.low, factor.high):
            try:
                scene_at(base, factor, value)
            except InputError as exc:
                raise InputError(f"--params {factor.name}={value:g}: {exc}") from None
    return tuple(factors)


def factor_levels(factor: Factor, levels: int) -> tuple[float, ...]:
    """`levels` evenly spaced values from low to high (levels >= 2)."""
    if levels < 2:
        raise InputError(f"--levels must be at least 2, got {levels}")
    return tuple(float(v) for v in np.linspace(factor.low, factor.high, levels))


# -- outcomes ---------------------------------------------------------------------------------
def outcome(row: Mapping[str, object]) -> str:
    """One virtual result row's outcome: 'success', 'stuck' (at the gap), 'fell', 'other'
    (a failure elsewhere, e.g. on a belt) or 'not_ok' (invalid, unstable, error)."""
    if row.get("status") != "ok":
        return "not_ok"
    if row.get("success") == 1:
        return "success"
    text = row.get("state_end_1") if row.get("y1") == 0 else row.get("state_end_2")
    state = json.loads(text) if isinstance(text, str) and text else []
    if len(state) < 7:
        return "other"
    x, z, sz = float(state[1]), float(state[3]), float(state[6])
    if z - sz < -FALL_DEPTH_M:
        return "fell"
    return "stuck" if abs(x) < GAP_ZONE_M else "other"


def yaw_band(theta_deg: float) -> str:
    """The yaw band of θ: the angle between the object's axis and the transfer direction,
    folded onto 0–90°."""
    folded = abs(((float(theta_deg) + 90.0) % 180.0) - 90.0)
    for name, lo, hi in YAW_BANDS:
        if lo <= folded < hi:
            return name
    return YAW_BANDS[-1][0]


def _groups(rows: Sequence[Mapping[str, object]]) -> dict[str, dict[str, np.ndarray]]:
    faces = np.array([str(r["face"]) for r in rows])
    conveyors = np.array([str(r["conveyor"]) for r in rows])
    bands = np.array([yaw_band(float(r["theta_deg"])) for r in rows])  # type: ignore[arg-type]
    pairs = np.array([f"{r['object_id']}/{r['face']}" for r in rows])
    return {
        "face": {f: faces == f for f in _FACES},
        "conveyor": {c: conveyors == c for c in _CONVEYORS},
        "yaw": {name: bands == name for name, _, _ in YAW_BANDS},
        "object_face": {p: pairs == p for p in sorted(set(pairs.tolist()))},
    }


def signature(
    rows: Sequence[Mapping[str, object]], success: np.ndarray
) -> dict[str, dict[str, float | None]]:
    """Success share by face, conveyor, yaw band and object/face pair ('o1/back');
    `success` is (runs, rows) or (rows,). A group without rows is None."""
    s = np.atleast_2d(np.asarray(success, dtype=float))
    out: dict[str, dict[str, float | None]] = {}
    for kind, masks in _groups(rows).items():
        out[kind] = {
            name: (float(s[:, m].mean()) if m.any() else None) for name, m in masks.items()
        }
    return out


def _auc(real_fail: np.ndarray, sim_fail: np.ndarray) -> float:
    from sklearn.metrics import roc_auc_score

    if real_fail.min() == real_fail.max():
        return math.nan
    return float(roc_auc_score(real_fail, sim_fail))


@dataclass(frozen=True)
class LevelResult:
    """The replay under one scene: one factor at one value (or the base scene).

    Attributes:
        factor: Factor name ('base' for the base scene).
        value: Factor value (NaN for the base scene).
        n: Virtual experiments (rows × runs).
        successes: Of those, successes.
        share, ci_low, ci_high: Success share and its Clopper–Pearson 95 % interval.
        outcomes: Count per `outcome` kind.
        stuck_share: Stuck-at-gap share of the failures (NaN without failures).
        f05: F0.5 against the real outcomes, mean over runs.
        auc: AUC of the per-row simulated failure share against real failure.
        signature: `signature` of the simulated successes.
    """

    factor: str
    value: float
    n: int
    successes: int
    share: float
    ci_low: float
    ci_high: float
    outcomes: dict[str, int]
    stuck_share: float
    f05: float
    auc: float
    signature: dict[str, dict[str, float | None]] = field(repr=False)

    def to_dict(self) -> dict[str, object]:
        """JSON-ready (NaN stays NaN; the caller makes it null)."""
        return {
            "factor": self.factor, "value": self.value, "n": self.n,
            "successes": self.successes, "share": self.share, "ci_low": self.ci_low,
            "ci_high": self.ci_high, "outcomes": dict(self.outcomes),
            "stuck_share": self.stuck_share, "f05": self.f05, "auc": self.auc,
            "signature": self.signature,
        }  # fmt: skip


def _level(
    factor: str,
    value: float,
    rows: Sequence[Mapping[str, object]],
    results: list[list[dict[str, object]]],
) -> LevelResult:
    kinds = [[outcome(row) for row in per_run] for per_run in results]
    success = np.array([[k == "success" for k in per_run] for per_run in kinds], dtype=int)
    actual = np.array([int(r["success"]) for r in rows])  # type: ignore[call-overload]
    counts = {k: sum(per_run.count(k) for per_run in kinds)
              for k in ("success", "stuck", "fell", "other", "not_ok")}  # fmt: skip
    n, k = int(success.size), int(success.sum())
    ci = clopper_pearson(k, n)
    failures = n - k
    f05 = float(np.mean([ConfusionMatrix.from_predictions(p, actual).f05 for p in success]))
    auc = _auc(1 - actual, 1.0 - success.mean(axis=0))
    return LevelResult(
        factor, float(value), n, k, k / n, ci.low, ci.high, counts,
        counts["stuck"] / failures if failures else math.nan, f05, auc,
        signature(rows, success),
    )  # fmt: skip


# -- running many scenes in one pool ----------------------------------------------------------
def _replay_scenes(
    rows: Sequence[Mapping[str, object]],
    scenes: Sequence[SceneConfig],
    *,
    runs: int,
    object_map: Mapping[str, str],
    seed: int,
    workers: int,
    units: str,
    on_progress: Callable[[int, int], None] | None,
) -> list[list[list[dict[str, object]]]]:
    """results[scene][run][row] for every scene, all replayed with the same seeds."""
    items = [
        ((s, spec.run, i), spec)
        for s, scene in enumerate(scenes)
        for run in range(runs)
        for i, spec in enumerate(replay_specs(rows, scene=scene, object_map=object_map,
                                              run=run, seed=seed, units=units))
    ]  # fmt: skip
    total = len(items)
    results: list[list[list[dict[str, object]]]] = [
        [[{} for _ in rows] for _ in range(runs)] for _ in scenes
    ]
    if on_progress is not None:
        on_progress(0, total)
    for done, ((s, run, i), row) in enumerate(run_tagged(items, workers), start=1):
        results[s][run][i] = row
        if on_progress is not None:
            on_progress(done, total)
    return results


def _prepare(
    rows: Sequence[Mapping[str, object]], runs: int, object_map: Mapping[str, str] | None
) -> dict[str, str]:
    check_real_rows(rows)
    if runs < 1:
        raise InputError(f"--runs must be at least 1, got {runs}")
    ids = sorted({str(r["object_id"]) for r in rows})
    return dict(object_map) if object_map is not None else parse_object_map(None, ids)


def _real(rows: Sequence[Mapping[str, object]]) -> dict[str, object]:
    actual = np.array([int(r["success"]) for r in rows])  # type: ignore[call-overload]
    ci = clopper_pearson(int(actual.sum()), len(actual))
    return {"n": len(actual), "successes": int(actual.sum()), "share": float(actual.mean()),
            "ci_low": ci.low, "ci_high": ci.high,
            "signature": signature(rows, actual)}  # fmt: skip


@dataclass(frozen=True)
class SensitivityResult:
    """A one-at-a-time sensitivity analysis: the base scene and every factor level."""

    factors: tuple[Factor, ...]
    base: LevelResult
    levels: tuple[LevelResult, ...]
    real: dict[str, object]
    runs: int
    n_rows: int
    seed: int
    object_map: dict[str, str]

    def of(self, factor: str) -> tuple[LevelResult, ...]:
        """The levels of one factor, low to high."""
        return tuple(lv for lv in self.levels if lv.factor == factor)

    def effects(self) -> list[dict[str, object]]:
        """Per factor: range (max − min over levels) of the success share, F0.5 and AUC,
        the largest stuck-at-gap share of failures; sorted by the share's range, largest
        first (ties by F0.5 range)."""
        out = []
        for f in self.factors:
            lv = self.of(f.name)
            shares = [x.share for x in lv]
            f05 = [x.f05 for x in lv]
            aucs = [x.auc for x in lv if math.isfinite(x.auc)]
            stuck = [x.stuck_share for x in lv if math.isfinite(x.stuck_share)]
            out.append({
                "factor": f.name, "low": f.low, "high": f.high,
                "share_range": max(shares) - min(shares),
                "share_min": min(shares), "share_max": max(shares),
                "f05_range": max(f05) - min(f05), "f05_best": max(f05),
                "auc_range": (max(aucs) - min(aucs)) if aucs else math.nan,
                "auc_best": max(aucs) if aucs else math.nan,
                "stuck_share_max": max(stuck) if stuck else math.nan,
            })  # fmt: skip
        return sorted(out, key=lambda e: (-e["share_range"], -e["f05_range"]))  # type: ignore[operator]

    def to_dict(self) -> dict[str, object]:
        """Everything, JSON-ready (NaN left for the writer to null)."""
        return {
            "method": "one-at-a-time", "runs": self.runs, "n_rows": self.n_rows,
            "seed": self.seed, "object_map": self.object_map,
            "definitions": {"gap_zone_m": GAP_ZONE_M, "fall_depth_m": FALL_DEPTH_M,
                            "yaw_bands_deg": [b[0] for b in YAW_BANDS], "interval":
                            "Clopper-Pearson 95 %"},
            "real": self.real, "base": self.base.to_dict(),
            "factors": [f.to_dict() for f in self.factors],
            "levels": [lv.to_dict() for lv in self.levels], "effects": self.effects(),
        }  # fmt: skip

    def csv_rows(self) -> list[dict[str, object]]:
        """One flat row per level (the base scene first)."""
        out = []
        for lv in (self.base, *self.levels):
            row: dict[str, object] = {
                "factor": lv.factor, "value": lv.value, "n": lv.n, "successes": lv.successes,
                "share": lv.share, "ci_low": lv.ci_low, "ci_high": lv.ci_high,
                "failures": lv.n - lv.successes, "stuck": lv.outcomes["stuck"],
                "fell": lv.outcomes["fell"], "other": lv.outcomes["other"],
                "not_ok": lv.outcomes["not_ok"], "stuck_share": lv.stuck_share,
                "f05": lv.f05, "auc": lv.auc,
            }  # fmt: skip
            for kind, groups in lv.signature.items():
                for name, share in groups.items():
                    row[f"{kind}_{name}"] = share
            out.append(row)
        return out


def one_at_a_time(
    rows: Sequence[Mapping[str, object]],
    *,
    base: SceneConfig,
    factors: Sequence[Factor] = FACTORS,
    levels: int = 3,
    runs: int = 1,
    object_map: Mapping[str, str] | None = None,
    seed: int = 0,
    workers: int = 1,
    units: str = "m",
    on_progress: Callable[[int, int], None] | None = None,
) -> SensitivityResult:
    """Replay `rows` under `base` and under each factor at `levels` values, others at base.

    Args:
        rows: Real result rows (as for `calibrate`).
        base: The base scene (profile).
        factors: Factors to vary (`parse_factors`).
        levels: Values per factor, evenly spaced over its range.
        runs: Repetitions per row and scene.
        object_map: Real id → object reference (None: built-in core of the same id).
        seed: Master seed; every scene uses the same per-row seeds.
        workers: Worker processes.
        units: Length unit of mapped mesh files.
        on_progress: Called with (done, total) experiments.
    """
    mapping = _prepare(rows, runs, object_map)
    plan = [(f, v) for f in factors for v in factor_levels(f, levels)]
    scenes: list[SceneConfig] = [base]
    index: list[int] = []
    for f, v in plan:
        scene = scene_at(base, f, v)
        if scene not in scenes:
            scenes.append(scene)
        index.append(scenes.index(scene))
    results = _replay_scenes(rows, scenes, runs=runs, object_map=mapping, seed=seed,
                             workers=workers, units=units, on_progress=on_progress)  # fmt: skip
    base_level = _level("base", math.nan, rows, results[0])
    level_results = tuple(
        _level(f.name, v, rows, results[s]) for (f, v), s in zip(plan, index, strict=True)
    )
    return SensitivityResult(tuple(factors), base_level, level_results, _real(rows), runs,
                             len(rows), seed, mapping)  # fmt: skip


# -- Morris screening -------------------------------------------------------------------------
@dataclass(frozen=True)
class MorrisResult:
    """Morris elementary effects (SALib) of each factor on the replay's outputs.

    Attributes:
        factors: The factors, in SALib's order.
        points: The sampled factor values, (n_points, k).
        outputs: Output name → values per point ('share', 'stuck_rate' = stuck-at-gap
            share of all experiments, 'f05', 'auc').
        indices: Output name → factor name → {'mu_star', 'mu_star_conf', 'sigma', 'mu'}.
        trajectories, levels, runs, n_rows, seed: The design.
    """

    factors: tuple[Factor, ...]
    points: np.ndarray
    outputs: dict[str, np.ndarray]
    indices: dict[str, dict[str, dict[str, float]]]
    trajectories: int
    levels: int
    runs: int
    n_rows: int
    seed: int
    real: dict[str, object]

    def ranking(self, output: str = "share") -> list[dict[str, object]]:
        """Factors by mu* of `output`, largest first."""
        rows = [{"factor": name, **vals} for name, vals in self.indices[output].items()]
        return sorted(rows, key=lambda r: -float(r["mu_star"]))  # type: ignore[arg-type]

    def to_dict(self) -> dict[str, object]:
        """JSON-ready."""
        return {
            "method": "morris", "trajectories": self.trajectories, "levels": self.levels,
            "runs": self.runs, "n_rows": self.n_rows, "seed": self.seed, "real": self.real,
            "factors": [f.to_dict() for f in self.factors],
            "points": self.points.tolist(),
            "outputs": {k: v.tolist() for k, v in self.outputs.items()},
            "indices": self.indices, "ranking": self.ranking(),
        }  # fmt: skip

    def csv_rows(self) -> list[dict[str, object]]:
        """One row per factor: mu*, its confidence half-width and sigma for every output."""
        out = []
        for f in self.factors:
            row: dict[str, object] = {"factor": f.name, "low": f.low, "high": f.high}
            for output, by_factor in self.indices.items():
                for key in ("mu_star", "mu_star_conf", "sigma"):
                    row[f"{output}_{key}"] = by_factor[f.name][key]
            out.append(row)
        return out


def morris_screening(
    rows: Sequence[Mapping[str, object]],
    *,
    base: SceneConfig,
    factors: Sequence[Factor] = FACTORS,
    trajectories: int = 4,
    levels: int = 4,
    runs: int = 1,
    object_map: Mapping[str, str] | None = None,
    seed: int = 0,
    workers: int = 1,
    units: str = "m",
    on_progress: Callable[[int, int], None] | None = None,
) -> MorrisResult:
    """Morris screening: `trajectories` one-at-a-time paths through the factors' grid of
    `levels` values (SALib's sampler and analyser); (k + 1) × trajectories scenes."""
    from SALib.analyze import morris as morris_analyze
    from SALib.sample import morris as morris_sample

    mapping = _prepare(rows, runs, object_map)
    if trajectories < 2:
        raise InputError(f"--trajectories must be at least 2, got {trajectories}")
    if levels < 2 or levels % 2:
        raise InputError(f"Morris needs an even --levels >= 2, got {levels}")
    if len(factors) < 2:
        raise InputError("Morris screening needs at least two factors")
    problem = {"num_vars": len(factors), "names": [f.name for f in factors],
               "bounds": [[f.low, f.high] for f in factors]}  # fmt: skip
    points = morris_sample.sample(problem, N=trajectories, num_levels=levels, seed=seed)
    scenes: list[SceneConfig] = []
    index: list[int] = []
    for point in points:
        scene = base
        for f, v in zip(factors, point, strict=True):
            scene = scene_at(scene, f, float(v))
        if scene not in scenes:
            scenes.append(scene)
        index.append(scenes.index(scene))
    results = _replay_scenes(rows, scenes, runs=runs, object_map=mapping, seed=seed,
                             workers=workers, units=units, on_progress=on_progress)  # fmt: skip
    per_scene = [_level("morris", math.nan, rows, r) for r in results]
    outputs = {
        "share": np.array([per_scene[s].share for s in index]),
        "stuck_rate": np.array([per_scene[s].outcomes["stuck"] / per_scene[s].n for s in index]),
        "f05": np.array([per_scene[s].f05 for s in index]),
        "auc": np.array([per_scene[s].auc for s in index]),
    }
    indices: dict[str, dict[str, dict[str, float]]] = {}
    for name, y in outputs.items():
        if not np.all(np.isfinite(y)):
            continue  # e.g. AUC with one real class
        si = morris_analyze.analyze(problem, points, y, num_levels=levels, seed=seed,
                                    print_to_console=False)  # fmt: skip
        indices[name] = {
            f.name: {key: float(si[key][j]) for key in ("mu", "mu_star", "sigma", "mu_star_conf")}
            for j, f in enumerate(factors)
        }
    return MorrisResult(tuple(factors), np.asarray(points), outputs, indices, trajectories,
                        levels, runs, len(rows), seed, _real(rows))  # fmt: skip
