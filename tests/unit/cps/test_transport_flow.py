"""The transport module's operation flow (Fig. 5.9a): forming the OTS from scanned boxes, and
the state machine navigate → dock → scan → transfer → resolve over both legs, with the
refusal paths ending the operation at the step that failed."""

from __future__ import annotations

import asyncio

import pytest

from transfertwin.cps.apps import (
    STEPS,
    Leg,
    StepResult,
    form_ots,
    legs_of,
    run_transport_operation,
)
from transfertwin.ots import ASSET_TM, ASSET_TU, BeltThresholds, Col, TransferDirection
from transfertwin.perception import AABB

TH = BeltThresholds()
ON_TU = AABB((0.26, 0.0, 0.05), (0.10, 0.07, 0.05))  # centre, half extents in F_T
ON_TM = AABB((-0.40, 0.0, 0.05), (0.10, 0.07, 0.05))
PICKUP, DELIVERY = TransferDirection.TU_TO_TM, TransferDirection.TM_TO_TU


def _form(boxes, direction=PICKUP, holds=()):
    return form_ots(boxes, direction, TH, obj="o5", tm="TM_1", unit="TU_A",
                    receiver_holds=holds)  # fmt: skip


def test_the_ots_is_formed_from_one_object_on_the_giving_unit_in_p_pre():
    pickup = _form([ON_TU])
    assert pickup.ok and pickup.reason == ""
    assert pickup.state[Col.A] == ASSET_TU and pickup.state[Col.T] == 0.0
    assert tuple(pickup.state[Col.X : Col.Z + 1]) == ON_TU.centre
    delivery = _form([ON_TM], DELIVERY)
    assert delivery.ok and delivery.state[Col.A] == ASSET_TM


@pytest.mark.parametrize(
    ("boxes", "direction", "holds", "reason"),
    [
        ([], PICKUP, (), "o5 not seen on TU_A, where the ledger has it"),
        ([ON_TM], PICKUP, (), "target belts occupied: 1 object(s) seen on TM_1 at x = -0.400 m"),
        ([ON_TU, ON_TM], PICKUP, (), "target belts occupied"),
        ([ON_TU], PICKUP, ("o3",), "target belts occupied: TM_1 holds o3"),
        ([ON_TU], DELIVERY, (), "target belts occupied: 1 object(s) seen on TU_A"),
        ([ON_TM], PICKUP, (), "seen on TM_1"),  # where the ledger does not have it
        ([], DELIVERY, (), "o5 not seen on TM_1"),
        ([ON_TU, AABB((0.05, 0.0, 0.05), (0.03, 0.03, 0.05))], PICKUP, (),
         "2 objects seen on TU_A at x = +0.260 m, x = +0.050 m"),
        # over the belts' side edge (y_max = 0.2 m): not a pre-transfer state
        ([AABB((0.26, 0.15, 0.05), (0.10, 0.07, 0.05))], PICKUP, (),
         "o5 is not in a pre-transfer state (Eq. 5.7)"),
        # reaching past the unit's far end (tu_x_max = 0.5 m)
        ([AABB((0.45, 0.0, 0.05), (0.10, 0.07, 0.05))], PICKUP, (), "x ∈ [+0.350, +0.550] m"),
    ],
)  # fmt: skip
def test_the_ots_is_refused_with_the_reason(boxes, direction, holds, reason):
    check = _form(boxes, direction, holds)
    assert not check.ok
    assert reason in check.reason, check.reason


class Module:
    """A transport module whose steps succeed except where `fail` says; its scan sees
    `seen[leg name]` and is judged by the real `form_ots`."""

    def __init__(self, fail=None, seen=None, y=None):
        self.fail = fail or {}  # (leg name, step) -> reason
        self.seen = seen or {"pick-up": [ON_TU], "delivery": [ON_TM]}
        self.y = y or {}
        self.calls: list[tuple[str, str]] = []
        self.resolved: list[tuple[str, bool]] = []

    def _step(self, state, leg, info=None):
        self.calls.append((leg.name, state))
        reason = self.fail.get((leg.name, state))
        return StepResult(reason is None, reason or "", info or {})

    async def navigate(self, leg):
        return self._step("navigating", leg, {"station": leg.unit[-1]})

    async def dock(self, leg):
        return self._step("docking", leg, {"x_mm": -7.5})

    async def form_ots(self, leg):
        self.calls.append((leg.name, "scanning"))
        check = _form(self.seen[leg.name], leg.direction)
        return StepResult(check.ok, check.reason, {"boxes": len(self.seen[leg.name])})

    async def transfer(self, leg):
        y = self.y.get(leg.name, 1)
        self.calls.append((leg.name, "transferring"))
        return StepResult(y == 1, "" if y == 1 else "did not arrive", {"y": y})

    async def resolve(self, leg, success):
        self.resolved.append((leg.name, success))


def _run(module):
    published: list[tuple[str, str | None]] = []

    async def on_state(state, leg):
        published.append((state, None if leg is None else leg.name))

    result = asyncio.run(run_transport_operation(module, legs_of("TU_A", "TU_C"), on_state))
    return result, published


def test_a_delivered_operation_takes_every_state_of_both_legs_in_order():
    module = Module()
    result, published = _run(module)
    assert result["status"] == "delivered" and result["failed_step"] is None
    assert (result["y_pickup"], result["y_delivery"]) == (1, 1)
    expected = [*STEPS, *STEPS, "idle"]
    assert result["states"] == expected == [s for s, _ in published]
    assert [leg for _, leg in published] == ["pick-up"] * 4 + ["delivery"] * 4 + [None]
    assert module.resolved == [("pick-up", True), ("delivery", True)]
    assert [leg["unit"] for leg in result["legs"]] == ["TU_A", "TU_C"]
    assert result["legs"][0]["docking"] == {"x_mm": -7.5}
    assert result["legs"][1]["transferring"] == {"y": 1}


@pytest.mark.parametrize(
    ("module", "status", "step", "reason", "states"),
    [
        (Module(fail={("pick-up", "navigating"): "no path"}), "failed at pick-up",
         "navigating", "no path", ["navigating"]),
        (Module(fail={("pick-up", "docking"): "no line"}), "failed at pick-up", "docking",
         "no line", ["navigating", "docking"]),
        (Module(seen={"pick-up": [], "delivery": [ON_TM]}), "failed at pick-up", "scanning",
         "o5 not seen on TU_A", ["navigating", "docking", "scanning"]),
        (Module(seen={"pick-up": [ON_TU, ON_TM], "delivery": [ON_TM]}), "failed at pick-up",
         "scanning", "target belts occupied", ["navigating", "docking", "scanning"]),
        (Module(y={"pick-up": 0}), "failed at pick-up", "transferring", "did not arrive",
         list(STEPS)),
        (Module(seen={"pick-up": [ON_TU], "delivery": [ON_TM, ON_TU]}),
         "failed at delivery", "scanning", "target belts occupied",
         [*STEPS, "navigating", "docking", "scanning"]),
        (Module(y={"delivery": 0}), "failed at delivery", "transferring", "did not arrive",
         [*STEPS, *STEPS]),
    ],
)  # fmt: skip
def test_a_failed_step_ends_the_operation_there_and_says_why(module, status, step, reason,
                                                             states):  # fmt: skip
    result, published = _run(module)
    assert result["status"] == status and result["failed_step"] == step
    assert reason in result["reason"]
    assert result["states"] == [*states, "idle"] == [s for s, _ in published]
    leg = status.removeprefix("failed at ")
    # the OTS of the failing leg is released without a ledger move; a failed pick-up
    # never starts the delivery
    assert module.resolved[-1] == (leg, False)
    assert (leg == "pick-up") == ("y_delivery" not in result)
    assert result["y_pickup" if leg == "pick-up" else "y_delivery"] == 0
    assert [c for c in module.calls if c[0] == leg][-1] == (leg, step)


def test_idle_is_published_even_when_a_step_raises():
    class Broken(Module):
        async def dock(self, leg):
            raise ConnectionError("unit unreachable")

    published = []

    async def on_state(state, leg):
        published.append(state)

    with pytest.raises(ConnectionError):
        asyncio.run(run_transport_operation(Broken(), legs_of("TU_A", "TU_C"), on_state))
    assert published == ["navigating", "docking", "idle"]


def test_legs_name_the_units_and_directions():
    pickup, delivery = legs_of("TU_B", "TU_D")
    assert pickup == Leg("pick-up", "TU_B", PICKUP) and pickup.index == 0
    assert delivery == Leg("delivery", "TU_D", DELIVERY) and delivery.index == 1
