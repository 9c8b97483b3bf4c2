"""The execution of a transport operation by a transport module (Sec. 5.4, Fig. 5.9a).

A transport operation is two sub-operations (legs): the **pick-up** at the source unit
(TU → TM, a_pre = TU) and the **delivery** at the target unit (TM → TU, a_pre = TM). Each
leg runs the flowchart of Fig. 5.9a:

    navigate → dock → form the OTS → transfer loop → resolve

* **navigating**: global navigation to the station's coarse pose;
* **docking**: laser-based final approach; the docking error emerges here;
* **scanning** (forming the OTS): a workspace scan of the docked pair; the OTS is formed only
  if the object is seen on the giving unit — where the ledger says it is — and nowhere else,
  the receiving unit's belts are free (nothing seen there, and for the transport module
  nothing its representation says it carries), and the object's observed state lies in the
  pre-transfer set P_pre of Eq. 5.7 (`form_ots`);
* **transferring**: the transfer loop of the OTS controller until success or failure;
* **resolve**: a success moves the object in the ledger and the flow goes on with the next
  leg; any failure ends the operation with the step that failed and why. Either way the
  module undocks (releases the OTS) at the end of the leg.

The module is 'idle' again when the operation has ended. `run_transport_operation` is the
state machine; what each step does is the `TransportSkills` of the caller (the CPS's virtual
transport module drives the navigation package on the shop floor, the MuJoCo environment and
the perception pipeline; a physical module would drive its own).
"""

from __future__ import annotations

import math
from collections.abc import Awaitable, Callable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Protocol

import numpy as np

from transfertwin.ots import (
    ASSET_TM,
    ASSET_TU,
    N_COLS,
    BeltThresholds,
    Col,
    Face,
    TransferDirection,
    conveyor_of,
    pre_transfer_set,
)
from transfertwin.perception import AABB

__all__ = [
    "STEPS",
    "Leg",
    "OtsCheck",
    "StepResult",
    "TransportSkills",
    "form_ots",
    "legs_of",
    "run_transport_operation",
    "transfer_step",
]

#: The transport module's states while it runs a leg, in order; 'idle' before and after.
STEPS = ("navigating", "docking", "scanning", "transferring")


@dataclass(frozen=True)
class Leg:
    """One sub-operation: dock at `unit` and transfer in `direction`.

    Attributes:
        name: 'pick-up' or 'delivery'.
        unit: The transfer unit docked at.
        direction: TU_TO_TM for a pick-up, TM_TO_TU for a delivery.
    """

    name: str
    unit: str
    direction: TransferDirection

    @property
    def index(self) -> int:
        """0 for the pick-up, 1 for the delivery (the seed index of the leg)."""
        return 0 if self.name == "pick-up" else 1


def legs_of(source: str, target: str) -> tuple[Leg, Leg]:
    """The two legs of a transport operation from `source` to `target`."""
    return (
        Leg("pick-up", source, TransferDirection.TU_TO_TM),
        Leg("delivery", target, TransferDirection.TM_TO_TU),
    )


@dataclass(frozen=True)
class StepResult:
    """What one step did: whether the flow may go on, why not, and what to record."""

    ok: bool
    reason: str = ""
    info: Mapping[str, object] = field(default_factory=dict)


def transfer_step(rec) -> StepResult:
    """The transferring step's result from the OTS controller's `TransferRecord`: y, the
    start state's validity, the conveyor and the end time recorded; not ok when the start
    state was outside P_pre (Eq. 5.7) or the object did not reach the receiver."""
    t_end = rec.t_end_s
    info = {"y": rec.y, "valid": rec.valid, "conveyor": rec.conveyor,
            "t_end_s": None if math.isnan(t_end) else round(t_end, 3)}  # fmt: skip
    if not rec.valid:
        return StepResult(False, "the controller's observed start state is not in "
                                 "P_pre (Eq. 5.7)", info)  # fmt: skip
    if rec.y != 1:
        return StepResult(False, f"the object did not reach the receiver "
                                 f"(failure state after {t_end:.2f} s)", info)  # fmt: skip
    return StepResult(True, info=info)


@dataclass(frozen=True)
class OtsCheck:
    """The outcome of forming the OTS (`form_ots`).

    Attributes:
        ok: The OTS is formed; the transfer may start.
        reason: Why not (one line), '' when formed.
        state: The observed pre-transfer state (11,) (Eq. 5.4, t = 0), None when the
            object was not found.
    """

    ok: bool
    reason: str
    state: np.ndarray | None = None


def _side(box: AABB, th: BeltThresholds) -> int:
    """ASSET_TM for a box whose centre is over the TM (x ≤ the TM's tip), else ASSET_TU."""
    return ASSET_TM if box.centre[0] <= th.tm_x_max else ASSET_TU


def _where(boxes: Sequence[AABB]) -> str:
    return ", ".join(f"x = {b.centre[0]:+.3f} m" for b in boxes)


def form_ots(
    boxes: Sequence[AABB],
    direction: TransferDirection,
    thresholds: BeltThresholds,
    *,
    obj: str,
    tm: str,
    unit: str,
    receiver_holds: Sequence[str] = (),
    face: str = "front",
) -> OtsCheck:
    """Form the OTS from what a workspace scan saw (Sec. 5.4, 5.5; Fig. 5.9a).

    Args:
        boxes: Detected objects in F_T (the scan of the docked pair).
        direction: TM_TO_TU (a_pre = TM) or TU_TO_TM (a_pre = TU).
        thresholds: The belt sets' thresholds (P_pre of Eq. 5.7).
        obj: The object to transfer (the ledger has it on the giving unit).
        tm, unit: Ids of the transport module and the docked transfer unit.
        receiver_holds: Objects the receiving unit's representation says lie on its belts.
        face: The face the object lies on (column f; P_pre does not read it).

    Returns:
        Formed, or refused with the reason: the receiving belts are occupied, the object is
        not seen on the giving unit, more than one object is seen there, or its observed
        state is not a pre-transfer state.
    """
    a_pre = ASSET_TM if direction is TransferDirection.TM_TO_TU else ASSET_TU
    giver, receiver = (tm, unit) if a_pre == ASSET_TM else (unit, tm)
    on_giver = [b for b in boxes if _side(b, thresholds) == a_pre]
    on_receiver = [b for b in boxes if _side(b, thresholds) != a_pre]
    if receiver_holds:
        return OtsCheck(False, f"target belts occupied: {receiver} holds "
                               f"{', '.join(receiver_holds)}")  # fmt: skip
    if on_receiver:
        return OtsCheck(False, f"target belts occupied: {len(on_receiver)} object(s) seen on "
                               f"{receiver} at {_where(on_receiver)}")  # fmt: skip
    if not on_giver:
        return OtsCheck(False, f"{obj} not seen on {giver}, where the ledger has it")
    if len(on_giver) > 1:
        return OtsCheck(False, f"{len(on_giver)} objects seen on {giver} at {_where(on_giver)}; "
                               f"its representation lists {obj} only")  # fmt: skip
    box = on_giver[0]
    s = np.full(N_COLS, math.nan)
    s[Col.A] = a_pre
    s[Col.X : Col.Z + 1] = box.centre
    s[Col.SX : Col.SZ + 1] = box.half
    s[Col.F] = Face[face.upper()]
    s[Col.C] = int(conveyor_of(box.centre[1], box.half[1]))
    s[Col.T] = 0.0
    pre = pre_transfer_set(thresholds, direction)
    if not pre.contains_one(s):
        lo, hi = box.lo, box.hi
        return OtsCheck(
            False,
            f"{obj} is not in a pre-transfer state (Eq. 5.7): seen at x ∈ [{lo[0]:+.3f}, "
            f"{hi[0]:+.3f}] m, y ∈ [{lo[1]:+.3f}, {hi[1]:+.3f}] m; {giver}'s belts span "
            f"x ∈ [{pre.x_min:+.3f}, {pre.x_max:+.3f}] m, y ∈ [{pre.y_min:+.3f}, "
            f"{pre.y_max:+.3f}] m",
            s,
        )
    return OtsCheck(True, "", s)


class TransportSkills(Protocol):
    """What a transport module does in each step of a leg (async: the CPS's event loop)."""

    async def navigate(self, leg: Leg) -> StepResult:
        """Drive to the coarse pose of `leg.unit`'s station."""
        ...

    async def dock(self, leg: Leg) -> StepResult:
        """Dock at `leg.unit` (info: the docking error)."""
        ...

    async def form_ots(self, leg: Leg) -> StepResult:
        """Scan the workspace and form the OTS (see `form_ots`)."""
        ...

    async def transfer(self, leg: Leg) -> StepResult:
        """Run the transfer loop; ok iff the object reached the receiver (info: y)."""
        ...

    async def resolve(self, leg: Leg, success: bool) -> None:
        """Record a successful transfer (ledger move); release the OTS (undock)."""
        ...


async def run_transport_operation(
    skills: TransportSkills,
    legs: Sequence[Leg],
    on_state: Callable[[str, Leg | None], Awaitable[None]],
) -> dict[str, object]:
    """Run the legs through the flow of Fig. 5.9a; never raises for a failed step.

    Args:
        skills: The module's steps.
        legs: The sub-operations, in order (`legs_of`).
        on_state: Called with each new state ('navigating', …, and 'idle' at the end) and
            the leg it belongs to (None for 'idle').

    Returns:
        ``status`` ('delivered', 'failed at pick-up', 'failed at delivery' — where the
        object is: at the source, or still on the transport module), ``y_pickup`` and, when
        the delivery was reached, ``y_delivery`` (Eq. 5.11; 0 when the OTS was never run),
        ``failed_step`` (a state of `STEPS`, None on success), ``reason``, ``states`` (the
        states in the order they were taken) and ``legs`` (per leg: unit and each step's
        record, e.g. the docking error).
    """
    states: list[str] = []
    out: dict[str, object] = {"status": "", "failed_step": None, "reason": "",
                              "states": states, "legs": []}  # fmt: skip
    steps = (("navigating", skills.navigate), ("docking", skills.dock),
             ("scanning", skills.form_ots), ("transferring", skills.transfer))  # fmt: skip
    try:
        for leg in legs:
            record: dict[str, object] = {"leg": leg.name, "unit": leg.unit}
            out["legs"].append(record)
            key = "y_pickup" if leg.name == "pick-up" else "y_delivery"
            out[key] = 0
            failed: tuple[str, str] | None = None
            for state, step in steps:
                states.append(state)
                await on_state(state, leg)
                result = await step(leg)
                record[state] = dict(result.info)
                if not result.ok:
                    failed = (state, result.reason)
                    break
            else:
                out[key] = 1
            await skills.resolve(leg, failed is None)
            if failed is not None:
                out["status"] = f"failed at {leg.name}"
                out["failed_step"], out["reason"] = failed
                return out
        out["status"] = "delivered"
        return out
    finally:
        states.append("idle")
        await on_state("idle", None)
