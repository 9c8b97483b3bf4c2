"""Predictions in operation (Sec. 7.2) measured on an emulated plant.

The Transport Module System uses the twin: when an order names an object, it places the
object in the twin's recommended pre-transfer state (its best state, Alg. 1–2) and, where
several transfer units can serve, docks at the one with the better docking record (the
smaller mean gap area in the plant's logged experiments). The baseline places at random
(face, θ and conveyor as in the calibration design) and docks where the plant's schedule
sends it. Both serve the same orders on the same plant.

One operation is one E^P cycle — the object handed over and back, as in the study's
experiments — and takes ``HANDLING_S`` (docking, placing the object) plus the plant's
transfer time (t_max when the object never reached a valid pre-transfer state) plus
``RECOVERY_S`` after a failure (an operator frees the object). Success rates get Wilson
intervals, their difference a Newcombe hybrid score interval; completed operations per
hour (successes / total time) get bootstrap percentile intervals over the operations.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping, Sequence

import numpy as np
from statsmodels.stats.proportion import proportion_confint

from transfertwin._errors import InputError
from transfertwin.ots import FACES, THETA_SINGLE
from transfertwin.plant import EmulatedPlant, PlantRequest
from transfertwin.sim import SceneConfig
from transfertwin.study.fullstate import AnalysisResult
from transfertwin.study.validation import newcombe_difference

__all__ = [
    "HANDLING_S",
    "POLICIES",
    "RECOVERY_S",
    "best_station",
    "docking_record",
    "operation_summary",
    "run_operations",
]

#: Seconds per operation for docking and placing the object (not simulated; a choice).
HANDLING_S = 20.0
#: Seconds an operator needs to free an object after a failed transfer (a choice).
RECOVERY_S = 60.0
#: The compared policies: the twin's recommendation, and random placement.
POLICIES = ("twin", "random")
_BOOTSTRAP = 2000


def docking_record(rows: Sequence[Mapping[str, object]]) -> dict[str, dict[str, float]]:
    """Per station of the plant's logged rows: experiments, mean gap area (cm²) and success
    share."""
    out: dict[str, dict[str, float]] = {}
    for station in sorted({str(r["transfer_unit"]) for r in rows}):
        mine = [r for r in rows if str(r["transfer_unit"]) == station]
        out[station] = {
            "n": len(mine),
            "mean_gap_area_cm2": float(np.mean([float(r["gap_area_cm2"]) for r in mine])),
            "success_share": float(np.mean([int(r["success"]) for r in mine])),
        }
    return out


def best_station(rows: Sequence[Mapping[str, object]]) -> str:
    """The station with the smaller mean gap area in the logged rows (ties: by name)."""
    record = docking_record(rows)
    if not record:
        raise InputError("no logged plant experiments to rate the stations by")
    return min(record, key=lambda s: (record[s]["mean_gap_area_cm2"], s))


def _random_state(rng: np.random.Generator) -> tuple[str, str, int]:
    face = FACES[int(rng.integers(len(FACES)))]
    theta = int(rng.integers(-179, 181))
    conveyor = ("left", "right")[int(rng.integers(2))] if theta in THETA_SINGLE else "both"
    return face, conveyor, theta


def _hours(rows: Sequence[Mapping[str, object]], t_max_s: float) -> np.ndarray:
    """Duration of each operation (h)."""
    out = []
    for r in rows:
        t = float(r["transfer_time_s"])
        t = t_max_s if math.isnan(t) else t
        out.append((HANDLING_S + t + (0.0 if int(r["success"]) else RECOVERY_S)) / 3600)
    return np.asarray(out)


def operation_summary(
    rows: Mapping[str, Sequence[Mapping[str, object]]], *, seed: int = 0, alpha: float = 0.05
) -> dict[str, object]:
    """Success rates (Wilson), their difference (Newcombe) and completed operations per hour
    (bootstrap) of the ``'twin'`` and ``'random'`` policies' operation rows."""
    t_max = SceneConfig().t_max_s
    rng = np.random.default_rng([seed, 0x4F505321])
    out: dict[str, object] = {}
    boot: dict[str, np.ndarray] = {}
    for policy in POLICIES:
        mine = rows[policy]
        y = np.array([int(r["success"]) for r in mine])
        hours = _hours(mine, t_max)
        n, k = len(y), int(y.sum())
        low, high = proportion_confint(k, n, alpha=alpha, method="wilson")
        idx = rng.integers(n, size=(_BOOTSTRAP, n))
        boot[policy] = y[idx].sum(axis=1) / hours[idx].sum(axis=1)
        out[policy] = {
            "n": n, "k": k, "success_rate": k / n,
            "success_low": float(low), "success_high": float(high),
            "ops_per_hour": k / float(hours.sum()),
            "ops_per_hour_low": float(np.quantile(boot[policy], alpha / 2)),
            "ops_per_hour_high": float(np.quantile(boot[policy], 1 - alpha / 2)),
            "hours": float(hours.sum()),
        }  # fmt: skip
    t, r = out["twin"], out["random"]
    diff = newcombe_difference(t["k"], t["n"], r["k"], r["n"], alpha)  # type: ignore[index]
    ratio = boot["twin"] / np.where(boot["random"] > 0, boot["random"], np.nan)
    ratio = ratio[np.isfinite(ratio)]
    out["success_diff"] = t["success_rate"] - r["success_rate"]  # type: ignore[index]
    out["success_diff_low"], out["success_diff_high"] = diff.low, diff.high
    out["success_significant"] = bool(diff.low > 0 or diff.high < 0)
    out["success_above_random"] = bool(diff.low > 0)
    r_ops = r["ops_per_hour"]  # type: ignore[index]
    out["ops_per_hour_ratio"] = t["ops_per_hour"] / r_ops if r_ops else math.inf  # type: ignore[index]
    if ratio.size:
        out["ops_per_hour_ratio_low"] = float(np.quantile(ratio, alpha / 2))
        out["ops_per_hour_ratio_high"] = float(np.quantile(ratio, 1 - alpha / 2))
    out["handling_s"], out["recovery_s"] = HANDLING_S, RECOVERY_S
    return out


def run_operations(
    plant: EmulatedPlant,
    analysis: AnalysisResult,
    logged_rows: Sequence[Mapping[str, object]],
    orders: int,
    *,
    seed: int = 0,
    workers: int = 1,
    on_progress: Callable[[int, int], None] | None = None,
) -> dict[str, object]:
    """Serve `orders` orders on `plant` with the twin's predictions and with random placement.

    Args:
        plant: The plant (its experiment ids continue).
        analysis: The twin's full-state analysis (best state per object).
        logged_rows: The plant's logged experiments (the docking record per station).
        orders: Orders per policy; each names an object drawn uniformly from those analysed.
        seed: Seed of the orders, the random placements and the bootstrap.
    """
    if orders < 1:
        raise InputError(f"orders must be at least 1, got {orders}")
    best = {s.object_id: s.best for s in analysis.selections}
    if not best:
        raise InputError("the twin's analysis has no object with a best state")
    objects = sorted(best)
    station = best_station(logged_rows)
    rng = np.random.default_rng([seed, 0x4F524452])
    named = [objects[int(i)] for i in rng.integers(len(objects), size=orders)]
    twin = [
        PlantRequest(o, best[o].face, best[o].conveyor, best[o].theta_deg, station) for o in named
    ]
    rand = [PlantRequest(o, *_random_state(rng)) for o in named]
    rows = {
        "twin": plant.operate(twin, workers=workers, on_progress=on_progress),
        "random": plant.operate(rand, workers=workers, on_progress=on_progress),
    }
    summary = operation_summary(rows, seed=seed)
    return {
        **summary,
        "orders": orders,
        "station": station,
        "docking_record": docking_record(logged_rows),
        "recommended": {
            o: {"face": b.face, "conveyor": b.conveyor, "theta_deg": b.theta_deg}
            for o, b in best.items()
        },
        "plant_experiments": 2 * orders,
    }
