"""The settings of adaptive sampling and the per-state interval it decides on.

Two interval kinds, chosen by `AdaptivePolicy.interval`:

* ``"beta"`` (default): the equal-tailed credible interval of the Jeffreys posterior
  Beta(k + ½, n − k + ½) at level `confidence`. A posterior does not depend on when one
  chose to stop (likelihood principle), so it is used unchanged at every look; how often a
  decision taken on it is wrong is measured, not promised (``benchmarks/
  adaptive_vs_exhaustive.py``, synthetic part).
* ``"clopper-pearson"``: the exact interval (Sec. 6.7) at level 1 − α/L, where L is the
  largest number of looks a state can get (`AdaptivePolicy.looks`). By Bonferroni over the
  looks, each state's interval then covers its success probability at every look at once
  with probability ≥ `confidence`: a frequentist guarantee per state, paid for with wider
  intervals (more runs).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import asdict, dataclass, fields

import numpy as np
from scipy.stats import beta as beta_dist

from transfertwin._errors import InputError
from transfertwin.study.fullstate import clopper_pearson_array

__all__ = ["ADAPTIVE_MAX_FACTOR", "INTERVAL_KINDS", "AdaptivePolicy", "adaptive_options"]

#: Values of `AdaptivePolicy.interval`.
INTERVAL_KINDS = ("beta", "clopper-pearson")


@dataclass(frozen=True)
class AdaptivePolicy:
    """How an adaptive study spends its runs (see `ObjectSampler` for the algorithm).

    Attributes:
        first_runs: Runs every state gets in the first round.
        batch_runs: Runs added to a state each time it is chosen in a later round.
        challengers: States sampled per round besides the leader, for best and for worst.
        confidence: Level of the per-state intervals, in (0, 1).
        interval: ``"beta"`` (Jeffreys posterior) or ``"clopper-pearson"`` (exact, Bonferroni
            over looks); module docstring.
        epsilon: Indifference zone: a best (worst) state is accepted once no other state can
            beat (undercut) it by more than this success share.
        window: Moving-average window of Eq. 6.27 the selection uses, odd degrees.
    """

    first_runs: int = 5
    batch_runs: int = 5
    challengers: int = 2
    confidence: float = 0.9
    interval: str = "beta"
    epsilon: float = 0.1
    window: int = 21

    def __post_init__(self) -> None:
        for name in ("first_runs", "batch_runs", "challengers"):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, int) or value < 1:
                raise InputError(f"adaptive {name} must be an integer >= 1, got {value!r}")
        if not 0.0 < float(self.confidence) < 1.0:
            raise InputError(f"adaptive confidence must be in (0, 1), got {self.confidence!r}")
        if self.interval not in INTERVAL_KINDS:
            kinds = ", ".join(INTERVAL_KINDS)
            raise InputError(f"adaptive interval must be one of {kinds}, got {self.interval!r}")
        if not 0.0 <= float(self.epsilon) < 1.0:
            raise InputError(f"adaptive epsilon must be in [0, 1), got {self.epsilon!r}")
        w = self.window
        if isinstance(w, bool) or not isinstance(w, int) or w < 1 or w % 2 == 0 or w > 361:
            raise InputError(f"adaptive window must be an odd integer in 1..361, got {w!r}")

    def looks(self, budget: int) -> int:
        """Most decisions a state can see: after the first round and after each batch."""
        return 1 + max(0, math.ceil((budget - self.first_runs) / self.batch_runs))

    def bounds(self, k: np.ndarray, n: np.ndarray, budget: int) -> tuple[np.ndarray, np.ndarray]:
        """Lower and upper bounds per state; a state without valid runs gets [0, 1].

        Args:
            k: Successes per state (integer array).
            n: Valid ('ok') runs per state, same shape.
            budget: Runs per state of the exhaustive plan (sets the look correction).
        """
        k, n = np.asarray(k, dtype=np.int64), np.asarray(n, dtype=np.int64)
        alpha = 1.0 - float(self.confidence)
        if self.interval == "clopper-pearson":
            low, high = clopper_pearson_array(k, n, alpha / self.looks(budget))
        else:
            low = np.where(k > 0, beta_dist.ppf(alpha / 2, k + 0.5, n - k + 0.5), 0.0)
            high = np.where(k < n, beta_dist.ppf(1 - alpha / 2, k + 0.5, n - k + 0.5), 1.0)
        empty = n == 0
        return np.where(empty, 0.0, low), np.where(empty, 1.0, high)

    def describe(self) -> dict[str, object]:
        """JSON-able settings (stored in the plan)."""
        return asdict(self)

    @classmethod
    def from_dict(cls, data: Mapping[str, object]) -> AdaptivePolicy:
        """Rebuild from `describe()`; unknown keys are an InputError."""
        names = {f.name for f in fields(cls)}
        unknown = sorted(set(data) - names)
        if unknown:
            raise InputError(f"unknown adaptive setting(s): {', '.join(unknown)}")
        return cls(**dict(data))  # type: ignore[arg-type]


#: A bounded adaptive prediction (a floor's on-the-fly one, a calibration campaign's): a
#: state gets at most this many times the average `runs` a state.
ADAPTIVE_MAX_FACTOR = 3


def adaptive_options(runs: int) -> tuple[tuple[str, object], ...]:
    """The adaptive settings of a bounded prediction with `runs` runs per state on
    average: every state ``runs // 2`` (at least 1) runs first, then batches of as many
    on the leader and two challengers of the best and of the worst race (`AdaptivePolicy`,
    its other settings the study's)."""
    half = max(1, runs // 2)
    return tuple(AdaptivePolicy(first_runs=half, batch_runs=half).describe().items())
