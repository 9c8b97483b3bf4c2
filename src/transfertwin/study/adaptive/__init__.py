"""Adaptive sampling of a full-state study: runs where they can change the best/worst answer."""

from transfertwin.study.adaptive._driver import AdaptiveOutcome, adaptive_policy, run_adaptive
from transfertwin.study.adaptive._policy import (
    ADAPTIVE_MAX_FACTOR,
    INTERVAL_KINDS,
    AdaptivePolicy,
    adaptive_options,
)
from transfertwin.study.adaptive._sampler import ObjectSampler, StateKey
from transfertwin.study.adaptive._synthetic import (
    SyntheticRun,
    agrees,
    selection_of_counts,
    simulate_bernoulli,
    smooth_landscape,
)

__all__ = [
    "ADAPTIVE_MAX_FACTOR",
    "INTERVAL_KINDS",
    "AdaptiveOutcome",
    "AdaptivePolicy",
    "ObjectSampler",
    "StateKey",
    "SyntheticRun",
    "adaptive_options",
    "adaptive_policy",
    "agrees",
    "run_adaptive",
    "selection_of_counts",
    "simulate_bernoulli",
    "smooth_landscape",
]
