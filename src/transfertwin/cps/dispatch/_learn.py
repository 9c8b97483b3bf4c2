"""The floor's own transfers as evidence: the twin's per-state predictions updated with
what the plant did (docs/architecture.md, "Operation").

The twin is calibrated against a handful of real experiments (Sec. 6.5); a floor runs
many transfers of both legs, each a real experiment E^P in a known pre-transfer state. The
predictive policy treats every finished transfer as one: per object, leg and state (face,
conveyor, θ), the successes k of n tries, and ranks the states by the posterior
probability that the whole operation succeeds,

    p(s) = p_pick-up(s) · p_delivery(s),

each leg a Beta–binomial posterior mean (w·m + k) / (w + n), its prior from the twin's
runs of that leg (`_predict`: an 'operation' prediction covers both):

- pick-up (TU → TM): prior mean from the twin's k_pickup of n_V runs,
  (k_pickup + ½) / (n_V + 1), worth w = min(n_V, `PRIOR_RUNS`) plant runs (the twin is not
  calibrated against this plant, so it counts as a few runs, not as many as it simulated);
- delivery (TM → TU): from the twin's k_V successful operations of the k_pickup runs whose
  pick-up succeeded, (k_V + ½) / (k_pickup + 1), worth min(k_pickup, `PRIOR_RUNS`); a
  round-trip study (there and back from the module) gives k_V of n_V instead;
- a leg the twin did not simulate (a round-trip study's pick-up; a state no run reached):
  Laplace's prior (m = ½, w = 2).

Learning alone (``[operation] twin = false``, the benchmark's baseline): no twin at all,
both legs start from the Laplace prior and every state of the grid is ranked by the
floor's own transfers only (`uninformed`); the order of the grid breaks ties, so an
object's first order is loaded in the default state.

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

__all__ = ["FACE_POOL", "LEGS", "PRIOR_RUNS", "fallback", "posterior", "record", "rerank",
           "state_key", "tries", "twin_priors", "uninformed"]  # fmt: skip

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


def tries(result: Mapping[str, Any],
          state: Mapping[str, Any] | None) -> list[tuple[str, Mapping[str, Any], int]]:  # fmt: skip
    """Every transfer that ran in a finished operation: (leg, state, y), in order.

    `state` is the state the object was loaded in (the plan's). A hand-over tried again
    lists each failed try in its ``retries`` (with the state it was in, where the station
    put the object down anew after a failed pick-up); the last try is the record itself,
    in the state the object was finally loaded in (``loaded_state``)."""
    out: list[tuple[str, Mapping[str, Any], int]] = []
    final = result.get("loaded_state") or state
    for leg in result.get("legs") or []:
        tr = leg.get("transferring")
        name = leg.get("leg")
        if not isinstance(tr, Mapping) or name not in LEGS:
            continue
        retries = tr.get("retries") or []
        for r in retries:
            s = r.get("state") or final
            if s:
                out.append((name, s, 0))
        last_failed_in_retries = bool(retries) and not tr.get("y")
        if tr.get("valid") and final and not last_failed_in_retries:
            out.append((name, final, int(tr.get("y") or 0)))
    return out


def record(evidence: dict[str, Any], obj: str, state: Mapping[str, Any] | None,
           result: Mapping[str, Any]) -> bool:  # fmt: skip
    """Add a finished operation's transfers to `evidence` (JSON: object -> leg -> state
    key -> [k, n]); False when it holds none (no known state, no transfer ran)."""
    if not state:
        return False
    found = tries(result, state)
    for leg, s, y in found:
        cell = evidence.setdefault(obj, {}).setdefault(leg, {}).setdefault(state_key(s), [0, 0])
        cell[0] += y
        cell[1] += 1
    return bool(found)


def _pooled(cells: Mapping[str, Sequence[int]], key: str) -> tuple[float, float]:
    face = key.split("/", 1)[0]
    k = n = 0.0
    for other, (ko, no) in cells.items():
        w = 1.0 if other == key else FACE_POOL if other.split("/", 1)[0] == face else 0.0
        k, n = k + w * ko, n + w * no
    return k, n


def uninformed(states: Sequence[Mapping[str, Any]]) -> list[dict[str, Any]]:
    """The states of the grid as predictions without a twin (k = n = 0, ``source`` 'none'),
    in the grid's order: what learning alone ranks."""
    return [{"face": s["face"], "conveyor": s["conveyor"], "theta_deg": int(s["theta_deg"]),
             "k": 0, "n": 0, "share": None, "source": "none"} for s in states]  # fmt: skip


def _twin_prior(k: float, n: float) -> tuple[float, float]:
    """(mean, weight) of a leg's prior from the twin's k successes of n runs."""
    return ((k + 0.5) / (n + 1.0), min(n, PRIOR_RUNS)) if n > 0 else _LAPLACE


def twin_priors(pred: Mapping[str, Any]) -> dict[str, tuple[float, float]]:
    """Per leg, (mean, weight) of the prior the twin's prediction `pred` gives it (module
    docstring; ``leg`` and ``k_pickup`` say which legs it simulated: a prediction without
    them is a round trip's)."""
    n_v, k_v = float(pred["n"]), float(pred["k"])
    kind, picked = pred.get("leg", "round-trip"), pred.get("k_pickup")
    if kind == "operation" and picked is not None:
        return {"pick-up": _twin_prior(float(picked), n_v),
                "delivery": _twin_prior(k_v, float(picked))}  # fmt: skip
    if kind == "pick-up":
        return {"pick-up": _twin_prior(k_v, n_v), "delivery": _LAPLACE}
    return {"pick-up": _LAPLACE, "delivery": _twin_prior(k_v, n_v)}


def posterior(pred: Mapping[str, Any], evidence: Mapping[str, Any]) -> dict[str, float]:
    """p_pickup, p_delivery and their product p for the state of `pred` (a ranked state of
    `transfertwin.cps.dispatch._predict`: face, conveyor, theta_deg, k, n, and for the legs
    of an operation leg and k_pickup) given one object's evidence (leg -> state key ->
    [k, n]). A state the twin did not simulate (n = 0: learning alone, `uninformed`) has
    Laplace's prior on both legs."""
    key = state_key(pred)
    priors = twin_priors(pred)
    out: dict[str, float] = {}
    for leg in LEGS:
        m, w = priors[leg]
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


def fallback(preds: Sequence[Mapping[str, Any]], evidence: Mapping[str, Any],
             best: Mapping[str, Any]) -> dict[str, Any] | None:  # fmt: skip
    """The state to put the object down in after a failed pick-up in `best`: the best
    state once that failure is counted (`rerank` with one more failed pick-up in `best`);
    None when no other state is ranked."""
    key = state_key(best)
    hypo = {leg: {k: list(v) for k, v in cells.items()} for leg, cells in evidence.items()}
    cell = hypo.setdefault("pick-up", {}).setdefault(key, [0, 0])
    cell[1] += 1
    other = next((p for p in rerank(preds, hypo) if state_key(p) != key), None)
    if other is None:
        return None
    return {"face": other["face"], "conveyor": other["conveyor"],
            "theta_deg": other["theta_deg"]}  # fmt: skip
