"""Adaptive sampling of one object's pre-transfer states: the pure algorithm.

No simulator here: `ObjectSampler` is told the outcomes of the runs it asked for and answers
with the runs it wants next, so the same code drives the study (`run_adaptive`) and a
synthetic Bernoulli model (`simulate_bernoulli`).

The answer it works towards is the one `analyze` gives (Eq. 6.27, Alg. 1–4): the best and
the worst *point* — a state of one series (Eq. 6.21–6.24) with its Eq. 6.27 window, the
states of that series within ±(window − 1)/2 degrees (on a 30° grid the window is the state
itself). A point's bounds are the means of its states' bounds (`AdaptivePolicy.bounds`),
which hold whenever the states' bounds hold.

Rounds. Round 0 gives every state `first_runs` runs. After each round, per object:

1. Leaders: `select` (Alg. 1–4, ties by the widening window) on the runs so far gives the
   best point b and the worst point w — the states `analyze` would report now.
2. Sequential elimination: a point whose upper bound is below the highest lower bound of
   any point can no longer be the best and is retired from the best race for good; one
   whose lower bound is above the lowest upper bound is retired from the worst race.
3. Challengers of b: points not retired, other than b (and not the same states as b),
   with U_c > L_b + ε: points that may still beat b by more than ε. Challengers of w:
   L_c < U_w − ε.
4. The best race is over when b has no challenger (separated within ε) or neither b nor
   any challenger can get more runs (exhaustive budget reached); likewise the worst.
5. Otherwise the next round adds `batch_runs` runs to the states of b (to narrow L_b) and of
   the `challengers` most dangerous challengers (highest U_c for the best, lowest L_c for
   the worst), as in LUCB (Kalyanakrishnan et al. 2012). Among equals, priority goes to the
   point whose θ-neighbours in its series (the grid states either side) have the higher
   pooled success share for the best (lower for the worst): the success probability is
   smoothed over θ to choose where to look first, never to decide.
6. The object is done when both races are over in the same round (a race is re-judged every
   round: runs spent on one race may move the other's leader).

Decisions use only runs 0..target−1 of each state, so they depend on the outcomes alone,
not on how a study was interrupted: replaying the rounds from stored results reproduces
them (resume), and a seed fixes them (determinism).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from transfertwin._errors import InputError
from transfertwin.ots import SERIES_ORDER
from transfertwin.study.adaptive._policy import AdaptivePolicy
from transfertwin.study.fullstate import SelectedState, StateStat, select

__all__ = ["ObjectSampler", "StateKey"]

#: A pre-transfer state of one object: (face, conveyor, theta_deg).
StateKey = tuple[str, str, int]


@dataclass(frozen=True)
class _Point:
    series: str
    theta_deg: int
    members: tuple[int, ...]  # state indices in the Eq. 6.27 window
    neighbours: tuple[int, ...]  # members plus the grid states either side


def _circular(a: int, b: int) -> int:
    d = abs(a - b) % 360
    return min(d, 360 - d)


def _points(states: Sequence[StateKey], window: int) -> tuple[_Point, ...]:
    half = (window - 1) // 2
    out = []
    for face, side in SERIES_ORDER:
        idx = sorted(
            (i for i, (f, c, _) in enumerate(states) if f == face and c in ("both", side)),
            key=lambda i: states[i][2],
        )
        m = len(idx)
        for pos, i in enumerate(idx):
            theta = states[i][2]
            members = tuple(j for j in idx if _circular(states[j][2], theta) <= half)
            near = {*members, idx[(pos - 1) % m], idx[(pos + 1) % m]}
            out.append(_Point(f"{face}-{side}", theta, members, tuple(sorted(near))))
    return tuple(out)


class ObjectSampler:
    """Adaptive sampling of one object's states (module docstring).

    Usage: ask `targets` (runs wanted per state, run indices 0..target−1), run them, pass
    every state's outcomes to `step`, repeat until `done`.

    Args:
        object_id: The object (labels the `select` input only).
        states: The object's states, in plan order.
        budget: Runs per state of the exhaustive plan; no state gets more.
        policy: The settings.
    """

    def __init__(
        self,
        object_id: str,
        states: Sequence[StateKey],
        budget: int,
        policy: AdaptivePolicy | None = None,
    ) -> None:
        if not states:
            raise InputError("adaptive sampling needs at least one state")
        if len(set(states)) != len(states):
            raise InputError("adaptive sampling: a state is listed twice")
        if isinstance(budget, bool) or not isinstance(budget, int) or budget < 1:
            raise InputError(f"adaptive sampling: budget must be an integer >= 1, got {budget!r}")
        self.object_id = object_id
        self.states: tuple[StateKey, ...] = tuple(states)
        self.budget = budget
        self.policy = policy or AdaptivePolicy()
        self._points = _points(self.states, self.policy.window)
        self._where = {(p.series, p.theta_deg): i for i, p in enumerate(self._points)}
        self._targets = np.full(len(self.states), min(self.policy.first_runs, budget), np.int64)
        self._retired: dict[str, set[int]] = {"best": set(), "worst": set()}
        #: How each race stood at the last step: None (running), "separated" or "budget".
        self.outcome: dict[str, str | None] = {"best": None, "worst": None}
        self.rounds = 0
        self.done = False

    @property
    def targets(self) -> dict[StateKey, int]:
        """Runs wanted per state now (run indices 0..target−1)."""
        return {s: int(t) for s, t in zip(self.states, self._targets, strict=True)}

    @property
    def runs(self) -> int:
        """Runs asked for so far (the sum of the targets)."""
        return int(self._targets.sum())

    def step(self, outcomes: Mapping[StateKey, Sequence[int | None]]) -> bool:
        """Decide the next round from the outcomes of the runs asked for.

        Args:
            outcomes: Per state, the outcome of run 0, 1, …: 1 success, 0 failure, None for
                a run without a valid result ('invalid', 'unstable', 'error'). At least
                `targets` entries per state; later entries are ignored.

        Returns:
            `done`: True once the best and the worst race are over (then `targets` stay).
        """
        if self.done:
            return True
        k = np.zeros(len(self.states), np.int64)
        n = np.zeros(len(self.states), np.int64)
        for i, s in enumerate(self.states):
            got = list(outcomes.get(s, ()))[: self._targets[i]]
            if len(got) < self._targets[i]:
                raise InputError(
                    f"adaptive sampling: {self.object_id} {s} has {len(got)} outcomes, "
                    f"{self._targets[i]} were asked for"
                )
            n[i] = sum(1 for v in got if v is not None)
            k[i] = sum(1 for v in got if v == 1)
        self.rounds += 1
        chosen = self._choose(k, n)
        open_ = self._targets < self.budget
        chosen = [i for i in chosen if open_[i]]
        if not chosen:
            self.done = True
            return True
        self._targets[chosen] = np.minimum(
            self.budget, self._targets[chosen] + self.policy.batch_runs
        )
        return False

    def _choose(self, k: np.ndarray, n: np.ndarray) -> set[int]:
        if not n.any():  # no valid run yet: every state needs more
            end = "budget" if (self._targets >= self.budget).all() else None
            self.outcome = {"best": end, "worst": end}
            return set(range(len(self.states)))
        low, high = self.policy.bounds(k, n, self.budget)
        stats = [
            StateStat(self.object_id, *s, int(n[i]), int(k[i]), k[i] / n[i], low[i], high[i])
            for i, s in enumerate(self.states)
            if n[i] > 0
        ]
        sel = select(stats, self.object_id, window=self.policy.window)
        pl = np.array([low[list(p.members)].mean() for p in self._points])
        pu = np.array([high[list(p.members)].mean() for p in self._points])
        pooled = np.array([
            k[list(p.neighbours)].sum() / max(1, n[list(p.neighbours)].sum()) for p in self._points
        ])  # fmt: skip
        chosen: set[int] = set()
        for race, leader in (("best", sel.best), ("worst", sel.worst)):
            chosen |= self._race(race, leader, pl, pu, pooled)
        return chosen

    def _open(self, point: int) -> bool:
        return bool((self._targets[list(self._points[point].members)] < self.budget).any())

    def _race(
        self,
        race: str,
        leader: SelectedState,
        pl: np.ndarray,
        pu: np.ndarray,
        pooled: np.ndarray,
    ) -> set[int]:
        eps = float(self.policy.epsilon)
        b = self._where[(leader.series, leader.theta_deg)]
        retired = self._retired[race]
        if race == "best":
            retired |= {c for c in range(len(pl)) if c != b and pu[c] < pl.max()}
            threat = pu - pl[b] - eps  # > 0: c may beat b by more than eps
            order = lambda c: (-pu[c], -pooled[c], c)  # noqa: E731
        else:
            retired |= {c for c in range(len(pl)) if c != b and pl[c] > pu.min()}
            threat = pu[b] - eps - pl
            order = lambda c: (pl[c], pooled[c], c)  # noqa: E731
        same = set(self._points[b].members)
        rivals = [
            c
            for c in range(len(pl))
            if c != b and c not in retired and threat[c] > 0
            and set(self._points[c].members) != same
        ]  # fmt: skip
        self.outcome[race] = None
        if not rivals:
            self.outcome[race] = "separated"
            return set()
        picks = [c for c in sorted(rivals, key=order) if self._open(c)][: self.policy.challengers]
        if self._open(b):
            picks.append(b)
        if not picks:
            self.outcome[race] = "budget"
            return set()
        return {i for c in picks for i in self._points[c].members}
