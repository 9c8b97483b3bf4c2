"""The floor's own transfers as evidence: the twin's per-state predictions updated with
what the plant did (issue 28, item 7; docs/architecture.md, "Operation").

The study's twin is calibrated against a handful of real experiments (Sec. 6.5) and
predicts the delivery leg (TM → TU) only; a floor runs many transfers of both legs, each a
real experiment E^P in a known pre-transfer state. The predictive policy treats every
finished transfer as one: per object, leg and state (face, conveyor, θ), the successes k
of n tries, and ranks the states by the posterior probability that the whole operation
succeeds,

    p(s) = p_pick-up(s) · p_delivery(s),

each leg a Beta–binomial posterior mean (w·m + k) / (w + n):

- delivery: prior mean m from the twin's k_V of n_V runs, (k_V + ½) / (n_V + 1), worth
  w = min(n_V, `PRIOR_RUNS`) plant runs (the twin is not calibrated against this plant, so
  it counts as a few runs, not as many as it simulated);
- pick-up (TU → TM): the twin has no prediction, so a Laplace prior (m = ½, w = 2).

Evidence is pooled within a face: the transfers of the object in other states on the same
face count with weight `FACE_POOL` (the face decides most of an object's outcome; θ and
the conveyor shift it). Only transfers that ran (a valid pre-transfer state, the transfer
loop run) are evidence; a module that went offline or a refused scan says nothing about
the state. The ranking uses only operations finished before the order is planned, so the
figures it is judged by are out of sample (prequential). Ties keep the twin's order.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

__all__ = ["FACE_POOL", "LEGS", "PRIOR_RUNS", "leg_outcomes", "posterior", "record", "rerank",
           "state_key"]  # fmt: skip

#: How many plant runs the twin's prediction of a state is worth at most.
PRIOR_RUNS = 4.0
#: Weight of an object's transfers in other states on the same face.
FACE_POOL = 0.5
#: The legs of an operation, as the transport flow names them.
LEGS = ("pick-up", "delivery")
#: The Laplace prior of a leg the twin does not predict: mean, weight.
_LAPLACE = (0.5, 2.0)


def state_key(state: Mapping[str, Any]) -> str:
    """'face/conveyor/θ' of a state: the evidence's key."""
    return f"{state['face']}/{state['conveyor']}/{int(state['theta_deg'])}"


def leg_outcomes(result: Mapping[str, Any]) -> dict[str, tuple[int, int]]:
    """(successes, tries) per leg whose transfer ran, from a finished operation's result.

    A delivery taken back and tried again counts every try: each entry of its
    ``retries`` is a failed try, and the last try is a success when y = 1."""
    out: dict[str, tuple[int, int]] = {}
    for leg in result.get("legs") or []:
        tr = leg.get("transferring")
        if not isinstance(tr, Mapping) or leg.get("leg") not in LEGS:
            continue
        failed = len(tr.get("retries") or [])
        y = int(tr.get("y") or 0) if tr.get("valid") else 0
        tries = failed + (1 if tr.get("valid") and (y or not failed) else 0)
        if tries:
            out[str(leg["leg"])] = (y, tries)
    return out


def record(evidence: dict[str, Any], obj: str, state: Mapping[str, Any] | None,
           result: Mapping[str, Any]) -> bool:  # fmt: skip
    """Add a finished operation's transfers to `evidence` (JSON: object -> leg -> state
    key -> [k, n]); False when it holds none (no known state, no transfer ran)."""
    if not state:
        return False
    outcomes = leg_outcomes(result)
    key = state_key(state)
    for leg, (k, n) in outcomes.items():
        cell = evidence.setdefault(obj, {}).setdefault(leg, {}).setdefault(key, [0, 0])
        cell[0] += k
        cell[1] += n
    return bool(outcomes)


def _pooled(cells: Mapping[str, Sequence[int]], key: str) -> tuple[float, float]:
    face = key.split("/", 1)[0]
    k = n = 0.0
    for other, (ko, no) in cells.items():
        w = 1.0 if other == key else FACE_POOL if other.split("/", 1)[0] == face else 0.0
        k, n = k + w * ko, n + w * no
    return k, n


def posterior(pred: Mapping[str, Any], evidence: Mapping[str, Any]) -> dict[str, float]:
    """p_pickup, p_delivery and their product p for the state of `pred` (a ranked state of
    `transfertwin.cps._predict`: face, conveyor, theta_deg, k, n) given one object's
    evidence (leg -> state key -> [k, n])."""
    key = state_key(pred)
    n_v = float(pred["n"])
    twin = ((float(pred["k"]) + 0.5) / (n_v + 1.0), min(n_v, PRIOR_RUNS))
    out: dict[str, float] = {}
    for leg, (m, w) in (("pick-up", _LAPLACE), ("delivery", twin)):
        k, n = _pooled(evidence.get(leg, {}), key)
        out[leg] = (w * m + k) / (w + n)
    return {"p_pickup": out["pick-up"], "p_delivery": out["delivery"],
            "p": out["pick-up"] * out["delivery"]}  # fmt: skip


def rerank(preds: Sequence[Mapping[str, Any]],
           evidence: Mapping[str, Any]) -> list[dict[str, Any]]:  # fmt: skip
    """The twin's ranked states of one object, each with its posterior (`posterior`),
    best first by p; ties keep the twin's order (a stable sort)."""
    scored = [{**p, **{k: round(v, 6) for k, v in posterior(p, evidence).items()}}
              for p in preds]  # fmt: skip
    return sorted(scored, key=lambda p: -p["p"])
