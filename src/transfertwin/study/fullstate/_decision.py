"""How to put an object on the belt, decided level by level as far as the data decide.

Alg. 1–4 (Sec. 6.6) always name one exact best state (face, conveyor, θ), even where many
states did equally well. An engineer decides top-down instead, and stops where the data
stop: first the face, then the conveyor on that face, then the yaw θ. `decide_placement`
does that over an object's per-state counts (`StateStat`, Eq. 6.26):

1. **Pool** the ``'ok'`` experiments of the level's options: per face over all states; per
   conveyor over the states of the faces kept at level 1; per θ over the states of the
   faces and conveyors kept above.
2. **Rank** the options by their share k/n (ties: more experiments, then the fixed order
   front, back / left, both, right / θ ascending); the first is the *lead*.
3. **Test** the lead against every other option with Fisher's exact test (two-sided, on
   the 2 × 2 table of successes and failures), Holm-adjusted over the level's comparisons
   at α = 0.05. An option whose adjusted p < α is *avoided*; the lead and every option not
   told apart from it are *kept* and go down to the next level.

Each level ends as one of (`LevelDecision.verdict`):

- ``decided``: one option kept, all others told apart from it;
- ``narrowed``: some options avoided, more than one kept;
- ``open``: none told apart from the lead: the choice does not matter as far as n shows;
- ``single``: only one option was run, so there was nothing to compare.

The exact best/worst state of Alg. 1–4 stays the study's formal answer; this is the
advice a person acts on. Pure: counts in, a frozen record out; the HTML report, the
`analyze` command, the console and the floor format it.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from dataclasses import dataclass

from scipy.stats import fisher_exact

from transfertwin._errors import InputError
from transfertwin.ots import CONVEYORS, FACES
from transfertwin.study.fullstate._states import StateStat

__all__ = [
    "DECISION_ALPHA",
    "LEVELS",
    "LevelDecision",
    "OptionCount",
    "PlacementDecision",
    "decide_placement",
]

#: Family-wise error rate of one level's comparisons (Holm).
DECISION_ALPHA = 0.05
#: The levels in the order they are decided.
LEVELS = ("face", "conveyor", "theta")


@dataclass(frozen=True)
class OptionCount:
    """One option of a level, pooled over the states kept above it.

    Attributes:
        value: ``'front'``, ``'left'`` or a θ as text (``'-90'``).
        k, n: Successes and ``'ok'`` experiments pooled over its states.
        p_adjusted: Holm-adjusted two-sided p of Fisher's exact test against the lead;
            ``None`` for the lead itself.
    """

    value: str
    k: int
    n: int
    p_adjusted: float | None = None

    @property
    def share(self) -> float:
        """k/n."""
        return self.k / self.n


@dataclass(frozen=True)
class LevelDecision:
    """What one level (face, conveyor or θ) decided.

    Attributes:
        level: One of `LEVELS`.
        options: The run options, lead first, then by share descending.
        kept: Options not told apart from the lead (the lead first).
        avoided: Options whose share is told apart below the lead's, in `options` order.
    """

    level: str
    options: tuple[OptionCount, ...]
    kept: tuple[str, ...]
    avoided: tuple[str, ...]

    @property
    def lead(self) -> OptionCount:
        """The option with the highest share."""
        return self.options[0]

    @property
    def verdict(self) -> str:
        """``'decided'``, ``'narrowed'``, ``'open'`` or ``'single'`` (module docstring)."""
        if len(self.options) == 1:
            return "single"
        if not self.avoided:
            return "open"
        return "decided" if len(self.kept) == 1 else "narrowed"

    def option(self, value: str) -> OptionCount:
        """The option named `value` (KeyError if it was not run)."""
        for opt in self.options:
            if opt.value == value:
                return opt
        raise KeyError(value)

    def to_dict(self) -> dict[str, object]:
        """Plain JSON-ready dict."""
        return {
            "level": self.level, "verdict": self.verdict, "kept": list(self.kept),
            "avoided": list(self.avoided),
            "options": [{"value": o.value, "k": o.k, "n": o.n, "p_adjusted": o.p_adjusted}
                        for o in self.options],
        }  # fmt: skip


@dataclass(frozen=True)
class PlacementDecision:
    """The face, conveyor and θ advice of one object (module docstring).

    Attributes:
        object_id: The object.
        face, conveyor, theta: The three levels, each decided within the options kept
            by the level above.
        alpha: The family-wise error rate of each level.
    """

    object_id: str
    face: LevelDecision
    conveyor: LevelDecision
    theta: LevelDecision
    alpha: float = DECISION_ALPHA

    @property
    def levels(self) -> tuple[LevelDecision, LevelDecision, LevelDecision]:
        """Face, conveyor, θ."""
        return (self.face, self.conveyor, self.theta)

    def to_dict(self) -> dict[str, object]:
        """Plain JSON-ready dict: the object, α and each level's `LevelDecision.to_dict`."""
        return {"object_id": self.object_id, "alpha": self.alpha,
                **{lv.level: lv.to_dict() for lv in self.levels}}  # fmt: skip


def _holm(p: Sequence[float]) -> list[float]:
    """Holm's step-down adjusted p-values, in the input order."""
    order = sorted(range(len(p)), key=lambda i: p[i])
    out, running = [0.0] * len(p), 0.0
    for rank, i in enumerate(order):
        running = max(running, min(1.0, (len(p) - rank) * p[i]))
        out[i] = running
    return out


def _fisher_p(a: OptionCount, b: OptionCount) -> float:
    table = [[a.k, a.n - a.k], [b.k, b.n - b.k]]
    return float(fisher_exact(table, alternative="two-sided").pvalue)


def _decide_level(level: str, pooled: dict[str, list[int]], order: Sequence[str],
                  alpha: float) -> LevelDecision:  # fmt: skip
    run = [OptionCount(v, *pooled[v]) for v in order if pooled.get(v, (0, 0))[1] > 0]
    run.sort(key=lambda o: (-o.share, -o.n))  # stable: ties keep the fixed order
    lead, rest = run[0], run[1:]
    p_adj = _holm([_fisher_p(lead, o) for o in rest])
    rest = [OptionCount(o.value, o.k, o.n, p) for o, p in zip(rest, p_adj, strict=True)]
    avoided = tuple(o.value for o in rest if o.p_adjusted < alpha and o.share < lead.share)
    kept = tuple(o.value for o in (lead, *rest) if o.value not in avoided)
    return LevelDecision(level, (lead, *rest), kept, avoided)


def _pool(states: Iterable[StateStat], key) -> dict[str, list[int]]:
    out: dict[str, list[int]] = {}
    for s in states:
        c = out.setdefault(key(s), [0, 0])
        c[0] += s.k
        c[1] += s.n
    return out


def decide_placement(
    states: Iterable[StateStat], object_id: str, *, alpha: float = DECISION_ALPHA
) -> PlacementDecision:
    """Decide face, then conveyor, then θ for `object_id` (module docstring).

    Args:
        states: Per-state statistics (`state_table`); other objects' states and states
            with n = 0 are ignored.
        object_id: The object to advise on.
        alpha: Family-wise error rate of each level's comparisons, in (0, 1).

    Returns:
        The three levels' decisions.

    Raises:
        InputError: If the object has no ``'ok'`` experiment or alpha is outside (0, 1).
    """
    if not 0.0 < alpha < 1.0:
        raise InputError(f"placement decision: alpha must be in (0, 1), got {alpha!r}")
    mine = [s for s in states if s.object_id == object_id and s.n > 0]
    if not mine:
        raise InputError(f"placement decision: object {object_id!r} has no 'ok' experiment")
    face = _decide_level("face", _pool(mine, lambda s: s.face), FACES, alpha)
    mine = [s for s in mine if s.face in face.kept]
    conveyor = _decide_level("conveyor", _pool(mine, lambda s: s.conveyor), CONVEYORS, alpha)
    mine = [s for s in mine if s.conveyor in conveyor.kept]
    thetas = [str(t) for t in sorted({s.theta_deg for s in mine})]
    theta = _decide_level("theta", _pool(mine, lambda s: str(s.theta_deg)), thetas, alpha)
    return PlacementDecision(object_id, face, conveyor, theta, alpha)
