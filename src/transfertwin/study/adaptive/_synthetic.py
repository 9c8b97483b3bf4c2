"""A synthetic Bernoulli model for adaptive sampling: known per-state success probabilities.

Run r of state i succeeds when u(i, r) < p_i, with u drawn from a `SeedSequence` keyed by
(seed, i), so the adaptive and the exhaustive sampling of one landscape see the same outcome
for the same run — as the study does, whose seeds depend on (object, state, run) only.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from transfertwin._errors import InputError
from transfertwin.study.adaptive._policy import AdaptivePolicy
from transfertwin.study.adaptive._sampler import ObjectSampler, StateKey
from transfertwin.study.fullstate import Selection, StateStat, clopper_pearson_array, select

__all__ = [
    "SyntheticRun",
    "agrees",
    "selection_of_counts",
    "simulate_bernoulli",
    "smooth_landscape",
]


def smooth_landscape(states: Sequence[StateKey], seed: int) -> dict[StateKey, float]:
    """Success probabilities that vary smoothly over θ, with plateaus near 0 and 1.

    Per face: p(θ) = logistic(4 (a + b cos(θ − φ) + c cos 2(θ − ψ)) + d_conveyor) with
    a ~ U(−1, 1), b ~ U(0.3, 1.5), c ~ U(0, 0.8), φ, ψ ~ U(0, 2π) and a conveyor offset
    d ~ U(−1, 1) for 'left' and 'right' states; drawn from `seed`.
    """
    rng = np.random.default_rng(seed)
    faces = {}
    for face in ("front", "back"):
        a, b, c = rng.uniform(-1, 1), rng.uniform(0.3, 1.5), rng.uniform(0, 0.8)
        phi, psi = rng.uniform(0, 2 * np.pi, 2)
        offsets = {"both": 0.0, "left": rng.uniform(-1, 1), "right": rng.uniform(-1, 1)}
        faces[face] = (a, b, c, phi, psi, offsets)
    out = {}
    for face, conveyor, theta in states:
        a, b, c, phi, psi, offsets = faces[face]
        t = np.deg2rad(theta)
        z = 4 * (a + b * np.cos(t - phi) + c * np.cos(2 * (t - psi))) + offsets[conveyor]
        out[(face, conveyor, theta)] = float(1 / (1 + np.exp(-z)))
    return out


def _draws(n_states: int, budget: int, seed: int) -> np.ndarray:
    return np.stack([
        np.random.default_rng(np.random.SeedSequence(seed, spawn_key=(i,))).random(budget)
        for i in range(n_states)
    ])  # fmt: skip


def selection_of_counts(
    object_id: str,
    states: Sequence[StateKey],
    k: Sequence[int],
    n: Sequence[int],
    window: int = 21,
) -> tuple[Selection, tuple[StateStat, ...]]:
    """What `analyze` reports for one object with these per-state counts (Alg. 1–4), and the
    per-state statistics with their Clopper–Pearson 95 % intervals."""
    k_arr, n_arr = np.asarray(k, np.int64), np.asarray(n, np.int64)
    low, high = clopper_pearson_array(k_arr, n_arr)
    y = k_arr / np.maximum(n_arr, 1)
    stats = tuple(
        StateStat(object_id, *s, int(n_arr[i]), int(k_arr[i]), y[i], low[i], high[i])
        for i, s in enumerate(states)
        if n_arr[i] > 0
    )
    return select(stats, object_id, window=window), stats


def agrees(
    pick: StateKey, reference: Selection, reference_stats: Sequence[StateStat], race: str
) -> bool:
    """The benchmark's criterion: `pick` is the reference's best (worst) state, or its
    reference success share lies inside the reference best's (worst's) 95 % interval."""
    ref = reference.best if race == "best" else reference.worst
    if pick == (ref.face, ref.conveyor, ref.theta_deg):
        return True
    share = {(s.face, s.conveyor, s.theta_deg): s.y_mean for s in reference_stats}.get(pick)
    return share is not None and ref.ci_low <= share <= ref.ci_high


@dataclass(frozen=True)
class SyntheticRun:
    """Adaptive against exhaustive sampling of one synthetic landscape.

    Attributes:
        adaptive, exhaustive: What `analyze` reports after each.
        exhaustive_stats: Per-state statistics of the exhaustive sampling.
        runs, budget_runs: Runs the adaptive sampling used; runs of the exhaustive one.
        rounds: Decisions the adaptive sampling took.
        true_best, true_worst: Highest and lowest true success probability.
        p_best, p_worst: True success probability of the adaptive best and worst state.
    """

    adaptive: Selection
    exhaustive: Selection
    exhaustive_stats: tuple[StateStat, ...]
    runs: int
    budget_runs: int
    rounds: int
    true_best: float
    true_worst: float
    p_best: float
    p_worst: float

    def agrees(self, race: str) -> bool:
        """`agrees` for the adaptive best (race 'best') or worst ('worst') state."""
        sel = self.adaptive.best if race == "best" else self.adaptive.worst
        pick = (sel.face, sel.conveyor, sel.theta_deg)
        return agrees(pick, self.exhaustive, self.exhaustive_stats, race)


def simulate_bernoulli(
    probs: Mapping[StateKey, float],
    budget: int,
    policy: AdaptivePolicy | None = None,
    seed: int = 0,
    object_id: str = "synthetic",
) -> SyntheticRun:
    """Adaptive sampling (`ObjectSampler`) and exhaustive sampling of one landscape.

    Args:
        probs: True success probability per state, in plan order.
        budget: Runs per state of the exhaustive sampling.
        policy: Adaptive settings (default `AdaptivePolicy()`).
        seed: Fixes every outcome.
        object_id: Label of the object.
    """
    states = tuple(probs)
    p = np.array([probs[s] for s in states], dtype=float)
    if not ((p >= 0) & (p <= 1)).all():
        raise InputError("synthetic success probabilities must lie in [0, 1]")
    wins = (_draws(len(states), budget, seed) < p[:, None]).astype(int)
    sampler = ObjectSampler(object_id, states, budget, policy)
    while not sampler.done:
        sampler.step({s: wins[i].tolist() for i, s in enumerate(states)})
    t = np.array([sampler.targets[s] for s in states])
    k = np.array([wins[i, : t[i]].sum() for i in range(len(states))])
    window = sampler.policy.window
    adaptive, _ = selection_of_counts(object_id, states, k, t, window)
    full, full_stats = selection_of_counts(
        object_id, states, wins.sum(axis=1), np.full(len(states), budget), window
    )
    truth = dict(zip(states, p, strict=True))
    return SyntheticRun(
        adaptive, full, full_stats, int(t.sum()), budget * len(states), sampler.rounds,
        float(p.max()), float(p.min()),
        truth[(adaptive.best.face, adaptive.best.conveyor, adaptive.best.theta_deg)],
        truth[(adaptive.worst.face, adaptive.worst.conveyor, adaptive.worst.theta_deg)],
    )  # fmt: skip
