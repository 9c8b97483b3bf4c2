"""One pre-transfer state compared between the virtual and the physical experiments
(Sec. 6.7): p̂_V and p̂_P with their Clopper–Pearson intervals and an interval for the
difference p_V − p_P by **Newcombe's hybrid score method** (Newcombe 1998, method 10: Wilson
score intervals of each side combined by square-and-add, no continuity correction), computed
by statsmodels' ``confint_proportions_2indep(method="newcomb", compare="diff")``.

`_validation` builds these comparisons from results tables and `_power` asks how many
experiments each would need; both import them from here.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import asdict, dataclass
from typing import Any

from statsmodels.stats.proportion import confint_proportions_2indep

from transfertwin._errors import InputError
from transfertwin.study.fullstate import clopper_pearson

__all__ = [
    "NEWCOMBE_HYBRID_SCORE",
    "DifferenceInterval",
    "StateComparison",
    "StateKey",
    "VirtualPhysicalShares",
    "newcombe_difference",
]

#: Value of `DifferenceInterval.method`.
NEWCOMBE_HYBRID_SCORE = "newcombe-hybrid-score"

StateKey = tuple[str, str, str, int]


@dataclass(frozen=True)
class DifferenceInterval:
    """Confidence interval for p₁ − p₂ of two independent binomials (Sec. 6.7).

    Attributes:
        low, high: Bounds in [-1, 1].
        estimate: k₁/n₁ − k₂/n₂.
        method: ``"newcombe-hybrid-score"``.
        alpha: 1 − confidence level.
    """

    low: float
    high: float
    estimate: float
    method: str = NEWCOMBE_HYBRID_SCORE
    alpha: float = 0.05

    @property
    def excludes_zero(self) -> bool:
        """True when 0 lies strictly outside [low, high]."""
        return self.low > 0.0 or self.high < 0.0


def newcombe_difference(
    k1: int, n1: int, k2: int, n2: int, alpha: float = 0.05
) -> DifferenceInterval:
    """Newcombe hybrid score interval (Newcombe 1998, method 10) for k₁/n₁ − k₂/n₂.

    Raises:
        InputError: On bad counts (see `clopper_pearson`), n₁ = 0, n₂ = 0 or bad alpha.
    """
    for k, n in ((k1, n1), (k2, n2)):
        clopper_pearson(k, n, alpha)  # validates counts and alpha
        if n == 0:
            raise InputError("the Newcombe interval needs n >= 1 on both sides (Sec. 6.7)")
    low, high = confint_proportions_2indep(
        k1, n1, k2, n2, method="newcomb", compare="diff", alpha=alpha
    )
    low, high = max(-1.0, float(low)), min(1.0, float(high))
    return DifferenceInterval(low, high, k1 / n1 - k2 / n2, NEWCOMBE_HYBRID_SCORE, float(alpha))


class VirtualPhysicalShares:
    """p̂_V and p̂_P of a state run by the twin (V) and the plant (P), for a dataclass with
    the fields ``k_v, n_v, k_p, n_p`` (successes and runs of each side, n ≥ 1)."""

    k_v: int
    n_v: int
    k_p: int
    n_p: int

    @property
    def p_v(self) -> float:
        """p̂_V = k_v / n_v (Eq. 6.26)."""
        return self.k_v / self.n_v

    @property
    def p_p(self) -> float:
        """p̂_P = k_p / n_p."""
        return self.k_p / self.n_p


@dataclass(frozen=True)
class StateComparison(VirtualPhysicalShares):
    """One pre-transfer state compared between E^V and E^P (Sec. 6.7, Fig. 6.24/6.25).

    Attributes:
        object_id, face, conveyor, theta_deg: The state.
        n_v, k_v: Virtual ``'ok'`` experiments and successes (n_v ≥ 1).
        ci_v_low, ci_v_high: Clopper–Pearson bounds of p_V.
        n_p, k_p: Physical ``'ok'`` experiments and successes (n_p ≥ 1).
        ci_p_low, ci_p_high: Clopper–Pearson bounds of p_P.
        diff_low, diff_high: Newcombe hybrid score bounds of p_V − p_P.
        alpha: 1 − confidence level of all three intervals.
    """

    object_id: str
    face: str
    conveyor: str
    theta_deg: int
    n_v: int
    k_v: int
    ci_v_low: float
    ci_v_high: float
    n_p: int
    k_p: int
    ci_p_low: float
    ci_p_high: float
    diff_low: float
    diff_high: float
    alpha: float = 0.05

    @property
    def key(self) -> StateKey:
        """``(object_id, face, conveyor, theta_deg)``."""
        return (self.object_id, self.face, self.conveyor, self.theta_deg)

    @property
    def difference(self) -> DifferenceInterval:
        """The interval of p_V − p_P as an object."""
        return DifferenceInterval(
            self.diff_low, self.diff_high, self.p_v - self.p_p, alpha=self.alpha
        )

    @property
    def significant(self) -> bool:
        """True when the interval of p_V − p_P excludes 0."""
        return self.difference.excludes_zero

    def to_dict(self) -> dict[str, Any]:
        """Plain dict of the fields; inverse of `from_dict`."""
        return asdict(self)

    @classmethod
    def from_dict(cls, data: Mapping[str, Any]) -> StateComparison:
        """Rebuild a comparison written by `to_dict`."""
        return cls(**data)
