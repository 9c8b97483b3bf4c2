"""How many experiments a validation (Sec. 6.7) needs before it can see a difference.

"0/2 objects differ" means little when every physical state was run once: the Newcombe
interval of p_V − p_P then spans about ±0.8 and no plausible difference can exclude 0.
`n_to_exclude_zero` answers the design question behind it: with n experiments on each
side, observing shares p₁ and p₂, from which n on does the Newcombe hybrid score interval
(Newcombe 1998, method 10, the interval `newcombe_difference` uses) exclude 0? The counts
are taken as k = p·n without rounding (the Wilson bounds are smooth in k), so the answer
is a property of the shares, not of a lucky rounding. `power_summary` applies it to every
compared state, for the observed difference and for a fixed detectable difference
(`DETECTABLE_DIFFERENCE`, 0.2) around the state's pooled share.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

from statsmodels.stats.proportion import confint_proportions_2indep

from transfertwin._errors import InputError
from transfertwin.study.validation._comparison import StateComparison

__all__ = [
    "DETECTABLE_DIFFERENCE",
    "N_MAX",
    "PowerSummary",
    "n_to_exclude_zero",
    "power_note",
    "power_summary",
]

#: Difference p_V − p_P a validation should be able to see (absolute, in shares).
DETECTABLE_DIFFERENCE = 0.2
#: Largest n per side `n_to_exclude_zero` searches; beyond it the answer is None.
N_MAX = 1_000_000


def _excludes_zero(p1: float, p2: float, n: int, alpha: float) -> bool:
    low, high = confint_proportions_2indep(
        p1 * n, n, p2 * n, n, method="newcomb", compare="diff", alpha=alpha
    )
    return bool(low > 0.0 or high < 0.0)


def n_to_exclude_zero(p1: float, p2: float, alpha: float = 0.05) -> int | None:
    """Smallest n per side for which the Newcombe interval of p₁ − p₂ excludes 0 (Sec. 6.7).

    Args:
        p1, p2: Success shares of the two sides, in [0, 1].
        alpha: 1 − confidence level.

    Returns:
        n ≥ 1, or None when p₁ = p₂ (no n suffices) or n would exceed `N_MAX`.

    Raises:
        InputError: If a share is outside [0, 1] or alpha outside (0, 1).
    """
    for p in (p1, p2):
        if not (isinstance(p, (int, float)) and 0.0 <= p <= 1.0):
            raise InputError(f"a success share must lie in [0, 1], got {p!r} (Sec. 6.7)")
    if not (isinstance(alpha, (int, float)) and 0.0 < alpha < 1.0):
        raise InputError(f"alpha must lie in (0, 1), got {alpha!r} (Sec. 6.7)")
    if p1 == p2 or not _excludes_zero(p1, p2, N_MAX, alpha):
        return None
    low, high = 0, 1  # invariant: high excludes 0, low does not (n = 0 never does)
    while not _excludes_zero(p1, p2, high, alpha):
        low, high = high, high * 2
    while high - low > 1:
        mid = (low + high) // 2
        if _excludes_zero(p1, p2, mid, alpha):
            high = mid
        else:
            low = mid
    return high


def _around(p: float, d: float) -> tuple[float, float]:
    """Shares p ± d/2, shifted inside [0, 1]."""
    centre = min(max(p, d / 2), 1.0 - d / 2)
    return centre + d / 2, centre - d / 2


@dataclass(frozen=True)
class PowerSummary:
    """What each compared state's n can show (Sec. 6.7); one entry per state, in order.

    Attributes:
        n_v, n_p: Virtual and physical ``'ok'`` experiments of each state.
        half_width: Half-width of each state's difference interval.
        n_detectable: n per side for which a difference of ``detectable`` around the
            state's pooled share would exclude 0 (None: beyond `N_MAX`).
        n_observed: n per side for which the observed difference would exclude 0
            (None: no difference observed, or beyond `N_MAX`).
        underpowered: Whether the state is not significant and its smaller side has fewer
            runs than ``n_detectable`` (a significant state evidently had the power).
        detectable: The detectable difference (`DETECTABLE_DIFFERENCE`).
        alpha: 1 − confidence level.
    """

    n_v: tuple[int, ...]
    n_p: tuple[int, ...]
    half_width: tuple[float, ...]
    n_detectable: tuple[int | None, ...]
    n_observed: tuple[int | None, ...]
    underpowered: tuple[bool, ...]
    detectable: float
    alpha: float

    def to_dict(self) -> dict[str, object]:
        """JSON-ready fields (the ``power`` entry of ``summary.json``)."""
        return {
            "detectable_difference": self.detectable, "alpha": self.alpha,
            "states_underpowered": sum(self.underpowered),
            "n_per_side_detectable": list(self.n_detectable),
            "n_per_side_observed": list(self.n_observed),
            "underpowered": list(self.underpowered),
        }  # fmt: skip


def power_summary(
    comparisons: Sequence[StateComparison], detectable: float = DETECTABLE_DIFFERENCE
) -> PowerSummary:
    """`n_to_exclude_zero` for every compared state (pure).

    Raises:
        InputError: If there is no comparison or ``detectable`` is not in (0, 1].
    """
    if not comparisons:
        raise InputError("no compared state to assess (Sec. 6.7)")
    if not 0.0 < detectable <= 1.0:
        raise InputError(
            f"the detectable difference must lie in (0, 1], got {detectable} (Sec. 6.7)"
        )
    alpha = comparisons[0].alpha
    n_det, n_obs, under = [], [], []
    for c in comparisons:
        need = n_to_exclude_zero(*_around((c.k_v + c.k_p) / (c.n_v + c.n_p), detectable), alpha)
        n_det.append(need)
        n_obs.append(n_to_exclude_zero(c.p_v, c.p_p, alpha))
        under.append(not c.significant and (need is None or min(c.n_v, c.n_p) < need))
    return PowerSummary(
        n_v=tuple(c.n_v for c in comparisons),
        n_p=tuple(c.n_p for c in comparisons),
        half_width=tuple((c.diff_high - c.diff_low) / 2 for c in comparisons),
        n_detectable=tuple(n_det),
        n_observed=tuple(n_obs),
        underpowered=tuple(under),
        detectable=float(detectable),
        alpha=float(alpha),
    )


def _span(values: Sequence[int | None]) -> str:
    known = sorted(v for v in values if v is not None)
    if not known:
        return ""
    return f"{known[0]}" if known[0] == known[-1] else f"{known[0]}–{known[-1]}"


def power_note(power: PowerSummary) -> str:
    """One paragraph for people about the states without the power to see a difference:
    their n, the width of their intervals and which n per side would show one (empty when
    no compared state is underpowered)."""
    picked = [i for i, u in enumerate(power.underpowered) if u]
    if not picked:
        return ""

    def pick(values: Sequence) -> list:
        return [values[i] for i in picked]

    states = len(power.underpowered)
    head = (
        "no power at this n"
        if len(picked) == states
        else f"{len(picked)}/{states} compared states have too few runs to see a difference"
    )
    width = math.fsum(pick(power.half_width)) / len(picked)
    text = (
        f"{head}: physical n = {_span(pick(power.n_p))} per state, virtual n = "
        f"{_span(pick(power.n_v))}, difference intervals ±{width:.2f} on average, so 'not "
        "significant' there does not mean 'no difference'."
    )
    conf = f"{100 * (1 - power.alpha):g} %"
    need = _span(pick(power.n_detectable))
    if need:
        text += (
            f" A {conf} Newcombe interval would exclude 0 for a difference of "
            f"{power.detectable:g} with n = {need} per side"
        )
    observed = _span(pick(power.n_observed))
    if observed:
        lead = "; " if need else f" A {conf} Newcombe interval would exclude 0 "
        text += f"{lead}for the observed differences with n = {observed} per side"
    return text + ("." if need or observed else "")
