"""Adaptive sampling of a full-state study: runs where they can change the best/worst answer."""

from transfertwin.study.adaptive._policy import INTERVAL_KINDS, AdaptivePolicy
from transfertwin.study.adaptive._sampler import ObjectSampler, StateKey
from transfertwin.study.adaptive._synthetic import (
    SyntheticRun,
    agrees,
    selection_of_counts,
    simulate_bernoulli,
    smooth_landscape,
)

__all__ = [
    "INTERVAL_KINDS",
    "AdaptivePolicy",
    "ObjectSampler",
    "StateKey",
    "SyntheticRun",
    "agrees",
    "selection_of_counts",
    "simulate_bernoulli",
    "smooth_landscape",
]
