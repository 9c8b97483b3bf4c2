"""The report's "what to do" list: how to put each object on the belt, and how sure that is.

Alg. 1–4 always name one best state, even where several states did equally well; the
advice says a conveyor and an angle only where the data single them out. The
**separation rule** decides that, per object, on the face of its best state b:

    b is *separated* on its face f  ⇔  some run state s of f (n ≥ 1) has a 95 %
    Clopper–Pearson interval wholly below b's:  ci_high(s) < ci_low(b).

- If b is separated, the advice names b's face, conveyor and θ ("turned 60°
  counter-clockwise"): somewhere on that face a placement is worse than b, and the data
  show it at 95 %.
- If not, no state of f is told apart from b, so the choice of conveyor and θ on f is a
  tie in these data: the advice says "any <f> placement works" when every state of f
  succeeded in all its runs, and "any <f> placement does about as well as another"
  otherwise (naming b only as Alg. 1–4's pick, and asking for more runs).
- If the best and worst state have the same ȳ^MA (Eq. 6.27), no state of the object
  stands out at all (`no_difference`).

The rule only narrows what is recommended on the best face; the face itself and the
state to avoid are given as before, with the best-vs-worst interval check.
"""

from __future__ import annotations

import html
from collections.abc import Iterable, Sequence

from transfertwin.study.fullstate import SelectedState, Selection, StateStat

__all__ = [
    "CONVEYOR_TEXT",
    "YMA",
    "advice_item",
    "best_is_separated",
    "ci_text",
    "no_difference",
    "state_short",
    "told_apart",
    "turn_text",
]

YMA = "ȳ<sup>MA</sup>"
CONVEYOR_TEXT = {
    "left": "on the <b>left</b> belt",
    "right": "on the <b>right</b> belt",
    "both": "centred across <b>both</b> belts",
}


def ci_text(st: SelectedState) -> str:
    """``0.63–1.00``: the 95 % Clopper–Pearson interval."""
    return f"{st.ci_low:.2f}–{st.ci_high:.2f}"


def state_short(st: SelectedState) -> str:
    """``front, both, θ = 60°``."""
    return f"{html.escape(st.face)}, {html.escape(st.conveyor)}, θ = {st.theta_deg}°"


def turn_text(theta: int) -> str:
    """The yaw θ (signed, -179..180) in words."""
    if theta == 0:
        return "aligned with the direction of travel (θ = 0°)"
    if theta == 180:
        return "turned round (θ = 180°)"
    way = "counter-clockwise" if theta > 0 else "clockwise"
    return f"turned <b>{abs(theta)}° {way}</b> (θ = {theta}°)"


def told_apart(sel: Selection) -> bool:
    """The best state's interval lies wholly above the worst's."""
    return sel.best.ci_low > sel.worst.ci_high


def no_difference(sel: Selection) -> bool:
    """Best and worst are one smoothed level: no state stands out (e.g. all succeeded)."""
    return sel.best.y_ma == sel.worst.y_ma


def best_is_separated(best: SelectedState | StateStat, states: Iterable[StateStat]) -> bool:
    """The separation rule: is some run state of the best's face told apart below it?

    Args:
        best: The best state (its ``face`` and ``ci_low`` are used).
        states: The object's states (any face; states with n = 0 are ignored).

    Returns:
        True iff a state s on ``best.face`` with n ≥ 1 has ci_high(s) < ci_low(best).
    """
    return any(s.face == best.face and s.n > 0 and s.ci_high < best.ci_low for s in states)


def _tie_text(b: SelectedState, face_states: Sequence[StateStat]) -> str:
    face = html.escape(b.face)
    m = len(face_states)
    if all(s.k == s.n for s in face_states):
        ns = sorted({s.n for s in face_states})
        runs = f"{ns[0]} of {ns[0]} times" if len(ns) == 1 else "in every run"
        return (
            f"<b>any {face} placement works</b>: all {m} {face} states run succeeded {runs}, "
            "so no conveyor or angle on that face did better than another in these data."
        )
    lo = min(s.k / s.n for s in face_states)
    hi = max(s.k / s.n for s in face_states)
    return (
        f"<b>any {face} placement does about as well as another</b>: no {face} state's "
        f"95 % interval lies wholly below the best's, so these data do not single out a "
        f"conveyor or angle on that face (its {m} states succeeded at rates "
        f"{lo:.2f}–{hi:.2f}; Alg. 1–4 picks {state_short(b)}, {b.k} of {b.n}, 95 % CI "
        f"{ci_text(b)}, a tie rather than a recommendation). Run more experiments per "
        "state to tell the placements on that face apart."
    )


def _place_text(b: SelectedState, states: Sequence[StateStat]) -> str:
    face = html.escape(b.face)
    face_states = [s for s in states if s.face == b.face and s.n > 0]
    if not best_is_separated(b, face_states):
        return f"put it on its <b>{face}</b> face; {_tie_text(b, face_states)} "
    return (
        f"put it on its <b>{face}</b> face "
        f"{CONVEYOR_TEXT.get(b.conveyor, html.escape(b.conveyor))}, {turn_text(b.theta_deg)}. "
        f"There it succeeded {b.k} of {b.n} times (95 % CI {ci_text(b)}; smoothed over "
        f"neighbouring angles {YMA} = {b.y_ma:.2f}). "
    )


def advice_item(sel: Selection, states: Sequence[StateStat]) -> str:
    """One ``<li>`` of "What to do" for an object.

    Args:
        sel: Its best/worst states (Alg. 1–4).
        states: Its per-state statistics (`state_table`), for the separation rule.
    """
    b, w = sel.best, sel.worst
    obj = html.escape(sel.object_id)
    if no_difference(sel):
        return (
            f"<li><b>{obj}</b>: no state stands out: the smoothed success rate is "
            f"{b.y_ma:.2f} at every state run (e.g. {b.k} of {b.n} at {state_short(b)}, "
            f"95 % CI {ci_text(b)}), so any of the tested placements does as well as any "
            "other in these data.</li>"
        )
    text = (
        f"<b>{obj}</b>: {_place_text(b, states)}"
        f"Avoid the <b>{html.escape(w.face)}</b> face "
        f"{CONVEYOR_TEXT.get(w.conveyor, html.escape(w.conveyor))} at θ = {w.theta_deg}° "
        f"({w.k} of {w.n}, 95 % CI {ci_text(w)})."
    )
    if b.ci_high < 0.5:
        text += (
            " <span class='warn'>Even the best state fails more often than it succeeds: "
            "this object needs another way of handling.</span>"
        )
    if told_apart(sel):
        text += " <span class='ok'>The intervals do not overlap: the difference is real.</span>"
    else:
        text += (
            " <span class='warn'>The intervals overlap: these data cannot yet tell the best "
            "state from the worst at 95 %; run more experiments at these states (more runs "
            "per state) before relying on the choice.</span>"
        )
    return f"<li>{text}</li>"
