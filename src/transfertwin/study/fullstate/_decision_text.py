"""A `PlacementDecision` in plain words: one headline and one line per level.

The same words serve the HTML report, the ``analyze`` command, the console and the
floor, so they are plain text (no markup): a caller that writes HTML escapes them.

- `placement_headline`: "Put it on its front face, on any conveyor, at any θ." — what to
  do, as far as the data decide, with the counts of the face level.
- `level_line`: "Face: decided: front 56/56 against back 6/56 (Fisher's exact test,
  p < 0.001)." — per level, its verdict in words with the pooled counts.
"""

from __future__ import annotations

from transfertwin.study.fullstate._decision import LevelDecision, OptionCount, PlacementDecision

__all__ = ["CONVEYOR_WORDS", "level_line", "placement_headline"]

#: Where the object starts across the belts, in words.
CONVEYOR_WORDS = {
    "left": "on the left belt",
    "right": "on the right belt",
    "both": "centred across both belts",
}
_LEVEL_NAME = {"face": "Face", "conveyor": "Conveyor", "theta": "Yaw θ"}
#: Verdicts in words, as the level lines write them.
VERDICT_WORDS = {
    "decided": "decided",
    "narrowed": "narrowed down",
    "open": "does not matter (as far as n shows)",
    "single": "only one option run",
}
#: A θ level lists its options one by one up to this many; more are summarised.
_LIST_MAX = 6


def _value(level: str, value: str) -> str:
    return f"{value}°" if level == "theta" else value


def _count(level: str, o: OptionCount) -> str:
    return f"{_value(level, o.value)} {o.k}/{o.n}"


def _p_text(p: float | None) -> str:
    if p is None:
        return ""
    return "p < 0.001" if p < 0.001 else f"p = {p:.3f}"


def _options_text(lv: LevelDecision, values: tuple[str, ...]) -> str:
    opts = [lv.option(v) for v in values]
    if lv.level == "theta" and len(opts) > _LIST_MAX:
        k, n = sum(o.k for o in opts), sum(o.n for o in opts)
        head = f"{len(opts)} angles ({k}/{n} in all)"
        if k in (0, n):
            return f"{head}, every one {'succeeded' if k else 'failed'} every time"
        lo, hi = min(o.share for o in opts), max(o.share for o in opts)
        return f"{head}, shares {lo:.2f} to {hi:.2f}"
    return ", ".join(_count(lv.level, o) for o in opts)


def _face_phrase(lv: LevelDecision) -> str:
    if lv.verdict == "open":
        return "on either face"
    return f"on its {lv.lead.value} face"


def _conveyor_phrase(lv: LevelDecision) -> str:
    if lv.verdict == "open":
        return "on any conveyor"
    kept = " or ".join(CONVEYOR_WORDS[v] for v in lv.kept)
    if lv.verdict == "narrowed":
        return f"{kept} (not {' or '.join(CONVEYOR_WORDS[v] for v in lv.avoided)})"
    return kept


def _theta_phrase(lv: LevelDecision) -> str:
    if lv.verdict == "open":
        return "at any θ"
    if lv.verdict == "narrowed":
        if len(lv.avoided) <= len(lv.kept) or len(lv.kept) > _LIST_MAX:
            return "at any θ but " + ", ".join(f"{v}°" for v in lv.avoided)
        return "at θ = " + " or ".join(f"{v}°" for v in lv.kept)
    return f"at θ = {lv.lead.value}°"


def placement_headline(decision: PlacementDecision) -> str:
    """ "Put it on its front face, on any conveyor, at any θ." (plain text).

    Names a conveyor or θ only where its level is decided or narrowed; a level with one
    option run names it with "(the only one run)".
    """
    parts = []
    for lv, phrase in zip(decision.levels, (_face_phrase, _conveyor_phrase, _theta_phrase),
                          strict=True):  # fmt: skip
        text = phrase(lv)
        if lv.verdict == "single":
            text += " (the only one run)"
        parts.append(text)
    return f"Put it {', '.join(parts)}."


def level_line(lv: LevelDecision) -> str:
    """One level's verdict with its pooled counts (plain text), e.g. "Face: decided:
    front 56/56 against back 6/56 (Fisher's exact test, p < 0.001)."."""
    name, verdict = _LEVEL_NAME[lv.level], VERDICT_WORDS[lv.verdict]
    if lv.verdict == "single":
        return f"{name}: {verdict}: {_count(lv.level, lv.lead)}."
    if lv.verdict == "open":
        closest = min(o.p_adjusted for o in lv.options[1:])  # type: ignore[type-var]
        return (f"{name}: {verdict}: {_options_text(lv, lv.kept)}; none told apart from "
                f"the best (smallest Holm-adjusted {_p_text(closest)}).")  # fmt: skip
    worst_p = max(lv.option(v).p_adjusted for v in lv.avoided)  # type: ignore[type-var]
    p = _p_text(worst_p)
    if len(lv.avoided) > 1 and worst_p >= 0.001:  # type: ignore[operator]
        p = p.replace("=", "≤")
    test = "Fisher's exact test" + (", Holm-adjusted" if len(lv.options) > 2 else "")
    return (f"{name}: {verdict}: {_options_text(lv, lv.kept)} against "
            f"{_options_text(lv, lv.avoided)} ({test}, {p}).")  # fmt: skip
