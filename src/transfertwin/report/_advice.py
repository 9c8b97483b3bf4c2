"""The report's "what to do" list, decided face → conveyor → θ as far as the data decide.

Each object gets the headline of `decide_placement` (`placement_headline`: "Put it on its
front face, on any conveyor, at any θ.") and one line per level with its pooled counts
and verdict: decided, narrowed down, or "does not matter (as far as n shows)". The exact
best and worst state of Alg. 1–4 are the study's formal answer and stand lower down, in
their own table (`formal_cell`); the advice never names one of them as the placement to
use unless the data single it out level by level.
"""

from __future__ import annotations

import html

from transfertwin.study.fullstate import (
    PlacementDecision,
    SelectedState,
    Selection,
    level_line,
    placement_headline,
)

__all__ = [
    "YMA",
    "advice_item",
    "ci_text",
    "formal_cell",
    "no_difference",
    "state_short",
    "told_apart",
]

YMA = "ȳ<sup>MA</sup>"


def ci_text(st: SelectedState) -> str:
    """``0.63–1.00``: the 95 % Clopper–Pearson interval."""
    return f"{st.ci_low:.2f}–{st.ci_high:.2f}"


def state_short(st: SelectedState) -> str:
    """``front, both, θ = 60°``."""
    return f"{html.escape(st.face)}, {html.escape(st.conveyor)}, θ = {st.theta_deg}°"


def told_apart(sel: Selection) -> bool:
    """The best state's interval lies wholly above the worst's."""
    return sel.best.ci_low > sel.worst.ci_high


def no_difference(sel: Selection) -> bool:
    """Best and worst are one smoothed level: no state stands out (e.g. all succeeded)."""
    return sel.best.y_ma == sel.worst.y_ma


def formal_cell(sel: Selection) -> str:
    """Whether Alg. 1–4's best and worst state are told apart, in words."""
    if no_difference(sel):
        return "no difference"
    return "yes" if told_apart(sel) else "no (their intervals overlap)"


def _kept_share(decision: PlacementDecision) -> tuple[int, int]:
    """Successes and runs pooled over the placements the advice keeps (the θ level's)."""
    opts = [decision.theta.option(v) for v in decision.theta.kept]
    return sum(o.k for o in opts), sum(o.n for o in opts)


def advice_item(decision: PlacementDecision) -> str:
    """One ``<li>`` of "What to do": the headline in bold, then one line per level."""
    obj = html.escape(decision.object_id)
    lines = "".join(f"<li>{html.escape(level_line(lv))}</li>" for lv in decision.levels)
    text = f"<b>{obj}: {html.escape(placement_headline(decision))}</b><ul>{lines}</ul>"
    k, n = _kept_share(decision)
    if 2 * k < n:
        text += (
            f"<span class='warn'>Over the placements kept it succeeded only {k} of {n} "
            "times: unless more runs single out a better one, this object needs another "
            "way of handling.</span>"
        )
    return f"<li>{text}</li>"
