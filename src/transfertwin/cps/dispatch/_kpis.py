"""A floor's key performance indicators from the TMS's operations (docs/architecture.md,
"Operation").

Every figure is computed from the operations' own records, nothing is kept on the side:

- operations per hour: delivered operations per hour of the window from the first order
  to the last end (wall clock), and per hour of modelled floor time (`floor_s` of each
  module's results, summed per module: the busiest module's time is the makespan);
- success share: delivered among the operations that ended in a transfer outcome, with its
  Clopper–Pearson 95 % interval (Eq. 6.27's interval, statsmodels' ``beta`` method). A
  fault (`is_fault`: a module that went offline or restarted, an error, an object lost
  before its order could start) is no transfer outcome: it is counted apart (``faults``,
  ``faults_by_reason``) and neither raises nor lowers the share;
- mean lead time: order to end, over finished operations;
- utilisation per transport module (assigned to end of its operations) and per transfer
  unit (its docked steps: docking, scanning, transferring), as shares of the window;
- failed operations by reason: the step each failed in (transfer outcomes only).
"""

from __future__ import annotations

from collections import Counter, defaultdict
from collections.abc import Iterable, Mapping
from typing import Any

__all__ = ["UNIT_STEPS", "is_fault", "kpis", "with_calibration"]

#: The steps that occupy a transfer unit.
UNIT_STEPS = ("docking", "scanning", "transferring")


def is_fault(result: Mapping[str, Any]) -> bool:
    """Whether an operation's result is a fault of the floor, not a transfer outcome: a
    module that went offline or restarted mid-operation, an error, an object lost before
    its order could start (``fault`` in the result, or its status says so)."""
    status = str(result.get("status", ""))
    return bool(result.get("fault")) or status.startswith(("failed while", "failed before",
                                                            "error"))  # fmt: skip


def _interval(k: int, n: int) -> tuple[float | None, float | None]:
    if n == 0:
        return None, None
    from statsmodels.stats.proportion import proportion_confint

    low, high = proportion_confint(k, n, alpha=0.05, method="beta")
    return float(low), float(high)


def _busy(steps: list[list[Any]], end: float) -> dict[str, float]:
    """Seconds each unit spent in `UNIT_STEPS` along one operation's step records
    ([t, state, unit]); a step lasts until the next record (the last: until `end`)."""
    out: dict[str, float] = defaultdict(float)
    if not steps:
        return out
    for (t, state, unit), nxt in zip(steps, [*steps[1:], [end, None, None]], strict=True):
        if unit and state in UNIT_STEPS:
            out[unit] += max(0.0, float(nxt[0]) - float(t))
    return out


def kpis(ops: Iterable[Mapping[str, Any]], modules: Iterable[str], units: Iterable[str],
         now: float) -> dict[str, Any]:  # fmt: skip
    """The KPIs of `ops` (the TMS's operation records) at time `now` (epoch s)."""
    ops = list(ops)
    finished = [o for o in ops if o["state"] == "finished"]
    faults = [o for o in finished if is_fault(o["result"])]
    outcomes = [o for o in finished if not is_fault(o["result"])]
    delivered = [o for o in outcomes if o["result"].get("status") == "delivered"]
    failed = [o for o in outcomes if o["result"].get("status") != "delivered"]
    start = min((o["submitted"] for o in ops), default=now)
    end = max((o.get("finished", now) for o in finished), default=now)
    end = now if len(finished) < len(ops) else end
    window = max(end - start, 1e-9)
    low, high = _interval(len(delivered), len(outcomes))
    module_busy: dict[str, float] = dict.fromkeys(modules, 0.0)
    module_floor: dict[str, float] = dict.fromkeys(modules, 0.0)
    unit_busy: dict[str, float] = dict.fromkeys(units, 0.0)
    for o in ops:
        m = o.get("module")
        if m is None or o.get("assigned") is None:
            continue
        stop = o.get("finished", now)
        module_busy[m] = module_busy.get(m, 0.0) + max(0.0, stop - o["assigned"])
        module_floor[m] = module_floor.get(m, 0.0) + float(
            (o.get("result") or {}).get("floor_s") or 0.0)
        for unit, s in _busy(o.get("steps", []), stop).items():
            unit_busy[unit] = unit_busy.get(unit, 0.0) + s
    makespan = max(module_floor.values(), default=0.0)
    per_floor_hour = round(3600.0 * len(delivered) / makespan, 3) if makespan > 0 else None
    reasons = Counter(o["result"].get("status", "failed") if not o["result"].get("failed_step")
                      else f"failed while {o['result']['failed_step']}"
                      for o in failed)  # fmt: skip
    fault_reasons = Counter(str(o["result"].get("reason") or o["result"].get("status"))
                            for o in faults)  # fmt: skip
    lead = [o["finished"] - o["submitted"] for o in finished if "finished" in o]
    return {
        "orders": len(ops),
        "finished": len(finished),
        "delivered": len(delivered),
        "failed": len(failed),
        "faults": len(faults),
        "in_progress": len(ops) - len(finished),
        "window_s": round(window, 3),
        "operations_per_hour": round(3600.0 * len(delivered) / window, 3) if ops else 0.0,
        "floor_makespan_s": round(makespan, 3),
        "operations_per_floor_hour": per_floor_hour,
        "success_share": len(delivered) / len(outcomes) if outcomes else None,
        "success_share_ci95": [low, high],
        "mean_lead_time_s": round(sum(lead) / len(lead), 3) if lead else None,
        "utilisation": {
            "modules": {m: round(b / window, 4) for m, b in sorted(module_busy.items())},
            "units": {u: round(b / window, 4) for u, b in sorted(unit_busy.items())},
        },
        "failed_by_reason": dict(sorted(reasons.items())),
        "faults_by_reason": dict(sorted(fault_reasons.items())),
    }


def with_calibration(k: Mapping[str, Any], calibration_s: float, modules: int) -> dict[str, Any]:
    """`kpis`' document with the floor time of calibration campaigns counted as a cost:
    ``calibration_floor_s`` (the units' cycle time of every campaign's E^P) and
    ``operations_per_floor_hour_with_calibration``, the delivered operations per hour of
    the modelled makespan plus that time shared by the `modules` (as
    `benchmarks/operations.py` charges a calibrated arm)."""
    out = dict(k)
    span = float(k.get("floor_makespan_s") or 0.0) + calibration_s / max(1, modules)
    out["calibration_floor_s"] = round(calibration_s, 3)
    out["operations_per_floor_hour_with_calibration"] = (
        round(3600.0 * int(k["delivered"]) / span, 3) if span > 0 else None
    )
    return out
