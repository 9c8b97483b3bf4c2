"""Who carries an order, to which unit, in which pre-transfer state (docs/architecture.md,
"Operation").

The protocol is an auction run by the TMS for the order at the head of its queue, as
Open-RMF's dispatcher runs one among fleet adapters: the TMS asks every eligible transport
module (online, idle, carrying nothing — or, for an object on a module, that module alone)
for a bid (`Bid`); each module answers from its own pose and its own navigation planner
with the time it expects to need (`estimate`) for every candidate target unit; the TMS's
evaluator picks the lowest cost. A module that does not answer within the bid timeout
takes no part. The policies differ in the evaluator and the state:

- ``nearest-idle``: the module with the shortest expected time, the destination's first
  unit, the object loaded as it always was (`DEFAULT_STATE`);
- ``predictive``: the object is loaded in the twin's best state for it (`_predict`), and
  the cost of a (module, unit) pair is the expected time per *successful* delivery,
  ``eta / p`` (a failed delivery is tried again: geometric number of tries). The twin has one
  model of a unit, so ``p`` is the same at every unit of a destination group and the unit
  choice follows the expected time; the state choice is where the twin pays.

Times are modelled floor time, not wall time: driving from the planner's path length at
the cruise speed, `DOCK_S` for the final approach and the scan, `TRANSFER_S` for a
transfer. The same figures give each finished operation's ``floor_s`` (its modelled
duration) for the floor-time KPIs.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

from transfertwin._errors import InputError

if TYPE_CHECKING:
    from transfertwin.cps.apps import FloorRobot

__all__ = ["DOCK_S", "TRANSFER_S", "Bid", "choose", "drive_s", "estimate", "floor_seconds"]

#: Modelled seconds of the final approach and the OTS scan at a station (a choice; the
#: rehearsal's operations take 20 s of handling too).
DOCK_S = 20.0
#: Modelled seconds of one transfer when its own simulated time is not known.
TRANSFER_S = 10.0
#: Detour factor of a straight line when the planner finds no path.
_DETOUR = 1.4


def drive_s(robot: FloorRobot, start: Sequence[float], station: str) -> float:
    """Seconds to drive from pose `start` to `station`'s coarse pose: the planner's path
    length at the cruise speed (a straight line with a detour factor if it finds none)."""
    import numpy as np

    from transfertwin.navigation import plan_path

    cfg, floor = robot.cfg, robot.floor
    goal = floor.station(station).coarse_pose(cfg.coarse_distance_m)
    try:
        length = plan_path(floor, cfg.robot, np.asarray(start, dtype=float), goal,
                           cfg.planner).length_m  # fmt: skip
    except InputError:
        length = _DETOUR * math.dist(start[:2], goal[:2])
    return length / cfg.robot.cruise_m_s


def estimate(robot: FloorRobot, stations: Mapping[str, str], source: str | None,
             targets: Sequence[str]) -> dict[str, float]:  # fmt: skip
    """A module's expected seconds to carry an object from `source` (None: it is on board)
    to each of `targets` (unit -> station in `stations`), from where the robot stands."""
    here = tuple(float(v) for v in robot.pose)
    base = 0.0
    if source is not None:
        base = drive_s(robot, here, stations[source]) + DOCK_S + TRANSFER_S
        here = tuple(robot.floor.station(stations[source]).goal_pose())
    return {t: round(base + drive_s(robot, here, stations[t]) + DOCK_S + TRANSFER_S, 3)
            for t in targets}  # fmt: skip


@dataclass(frozen=True)
class Bid:
    """One module's answer: expected seconds per candidate target unit."""

    module: str
    eta_s: Mapping[str, float]


def choose(bids: Sequence[Bid], policy: str, p_success: float | None) -> tuple[str, str, float]:
    """The evaluator: (module, target unit, cost) of the lowest cost; ties go to the module
    and unit that sort first, so the choice is deterministic.

    Args:
        bids: The modules' bids (at least one).
        policy: ``nearest-idle`` (cost = expected time) or ``predictive`` (expected time per
            successful delivery, eta / p).
        p_success: The twin's success share of the chosen state (predictive; None or 0: the
            time alone).
    """
    if not bids:
        raise ValueError("no bids")
    p = p_success if policy == "predictive" and p_success else 1.0
    options = [(eta / p, b.module, unit) for b in bids for unit, eta in b.eta_s.items()]
    cost, module, unit = min(options, key=lambda o: (round(o[0], 6), o[1], o[2]))
    return module, unit, cost


def floor_seconds(result: Mapping[str, Any], robot: FloorRobot, start: Sequence[float],
                  stations: Mapping[str, str]) -> float:  # fmt: skip
    """The modelled floor time of a finished operation from its result's legs: driving to
    each leg's station (the navigated drive time when the module drove, else the planner's
    estimate from the previous stop), `DOCK_S` per docking and each transfer's simulated
    time (`TRANSFER_S` when it has none)."""
    total, here = 0.0, tuple(float(v) for v in start)
    for leg in result.get("legs", []):
        unit = leg.get("unit")
        nav = leg.get("navigating")
        if nav is None or unit not in stations:
            break
        total += float(nav.get("drive_s") or drive_s(robot, here, stations[unit]))
        here = tuple(robot.floor.station(stations[unit]).goal_pose())
        if "docking" in leg:
            total += DOCK_S
        tr = leg.get("transferring")
        if tr is not None:
            tries = 1 + len(tr.get("retries", []))
            total += tries * float(tr.get("t_end_s") or TRANSFER_S)
    return round(total, 3)
