"""Adaptive sampling on synthetic Bernoulli landscapes with known success probabilities."""

from __future__ import annotations

import json

import numpy as np
import pytest

from transfertwin._errors import InputError
from transfertwin.ots import experiment_states, filter_theta_step
from transfertwin.store import MemoryResultStore
from transfertwin.study.adaptive import (
    AdaptivePolicy,
    ObjectSampler,
    adaptive_policy,
    simulate_bernoulli,
    smooth_landscape,
)
from transfertwin.study.docking import FixedDockingError
from transfertwin.study.experiment import StudyPlan, run_study

STATES = [(s.face, s.conveyor, s.theta_deg) for s in filter_theta_step(experiment_states(), 30)]


def test_finds_the_true_best_and_worst_with_far_fewer_runs():
    eps = AdaptivePolicy().epsilon
    runs = budget = hits_best = hits_worst = 0
    n = 24
    for seed in range(n):
        r = simulate_bernoulli(smooth_landscape(STATES, seed), 50, seed=100 + seed)
        hits_best += r.true_best - r.p_best <= eps
        hits_worst += r.p_worst - r.true_worst <= eps
        runs, budget = runs + r.runs, budget + r.budget_runs
    assert hits_best >= n - 1 and hits_worst >= n - 1  # within the indifference zone
    assert runs / budget < 0.3


def test_a_clear_best_and_worst_are_found_exactly_and_cheaply():
    probs = dict.fromkeys(STATES, 0.5)
    probs[STATES[5]], probs[STATES[20]] = 0.98, 0.02
    for seed in range(5):
        r = simulate_bernoulli(probs, 50, seed=seed)
        best, worst = r.adaptive.best, r.adaptive.worst
        assert (best.face, best.conveyor, best.theta_deg) == STATES[5]
        assert (worst.face, worst.conveyor, worst.theta_deg) == STATES[20]
        assert r.runs < 0.25 * r.budget_runs


def test_same_seed_same_runs_and_answer():
    probs = smooth_landscape(STATES, 3)
    a, b = simulate_bernoulli(probs, 40, seed=9), simulate_bernoulli(probs, 40, seed=9)
    assert (a.runs, a.rounds, a.adaptive) == (b.runs, b.rounds, b.adaptive)


def test_decisions_ignore_runs_beyond_the_targets():
    # An interrupted round leaves extra stored runs; replay must decide as without them.
    rng = np.random.default_rng(0)
    p = np.array(list(smooth_landscape(STATES, 5).values()))
    wins = (rng.random((len(STATES), 30)) < p[:, None]).astype(int)
    exact, padded = ObjectSampler("o", STATES, 30), ObjectSampler("o", STATES, 30)
    while not exact.done:
        t = exact.targets
        exact.step({s: wins[i, : t[s]].tolist() for i, s in enumerate(STATES)})
        padded.step({s: wins[i].tolist() for i, s in enumerate(STATES)})
        assert padded.targets == exact.targets
    assert padded.done


def test_flat_landscape_stops_at_the_budget():
    sampler = ObjectSampler("o", STATES, 12, AdaptivePolicy(epsilon=0.0))
    while not sampler.done:
        sampler.step({s: [1] * 12 for s in STATES})
    assert max(sampler.targets.values()) == 12
    assert sampler.runs <= 12 * len(STATES)


def test_invalid_runs_count_towards_the_budget_not_the_interval():
    sampler = ObjectSampler("o", STATES[:4], 6)
    while not sampler.done:
        sampler.step(dict.fromkeys(STATES[:4], [None] * 6))
    assert sampler.targets == dict.fromkeys(STATES[:4], 6)
    assert sampler.outcome == {"best": "budget", "worst": "budget"}


def test_clopper_pearson_bounds_are_corrected_for_looks():
    k, n = np.array([3]), np.array([10])
    cp = AdaptivePolicy(interval="clopper-pearson", confidence=0.95)
    lo50, hi50 = cp.bounds(k, n, 50)
    lo5, hi5 = cp.bounds(k, n, 5)  # one look: the plain 95 % interval
    assert cp.looks(50) == 10 and cp.looks(5) == 1
    assert lo50[0] < lo5[0] and hi50[0] > hi5[0]
    assert lo5[0] == pytest.approx(0.0667, abs=1e-3) and hi5[0] == pytest.approx(0.6525, abs=1e-3)
    lo, hi = AdaptivePolicy().bounds(np.array([0, 5]), np.array([0, 5]), 50)
    assert (lo[0], hi[0], hi[1]) == (0.0, 1.0, 1.0) and 0.5 < lo[1] < 1.0


@pytest.mark.parametrize(
    "bad",
    [{"first_runs": 0}, {"confidence": 1.0}, {"interval": "wald"}, {"epsilon": -0.1},
     {"window": 4}, {"batch_runs": True}],
)  # fmt: skip
def test_policy_rejects_bad_settings(bad):
    with pytest.raises(InputError):
        AdaptivePolicy(**bad)
    with pytest.raises(InputError, match="unknown adaptive"):
        AdaptivePolicy.from_dict({"speed": 2})


def _plan(**kw) -> StudyPlan:
    return StudyPlan(("o1",), 180, 4, 0, FixedDockingError(), **kw)


def test_plan_records_the_sampling_and_keeps_exhaustive_hashes():
    exhaustive = _plan()
    assert "sampling" not in json.loads(exhaustive.to_json())
    policy = AdaptivePolicy(epsilon=0.2)
    adaptive = _plan(sampling="adaptive", sampling_options=tuple(policy.describe().items()))
    stored = json.loads(adaptive.to_json())["sampling"]
    assert stored["mode"] == "adaptive" and stored["epsilon"] == 0.2
    again = StudyPlan.from_json(adaptive.to_json())
    assert again == adaptive and again.plan_hash == adaptive.plan_hash != exhaustive.plan_hash
    assert adaptive_policy(again) == policy
    with pytest.raises(InputError, match="run_adaptive"):
        run_study(adaptive, MemoryResultStore())
    with pytest.raises(InputError):
        _plan(sampling_options=(("epsilon", 0.2),))
