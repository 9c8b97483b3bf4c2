"""The TMS's order book (`cps.dispatch.OrderBook`): the ledger decides what a module carries,
not the module's last heartbeat, which may still list an object it has just handed over."""

from __future__ import annotations

import pytest

from transfertwin.cps.dispatch import OrderBook
from transfertwin.cps.floor import default_floor_spec
from transfertwin.cps.opcua import OperationRefused


def _book() -> OrderBook:
    floor = default_floor_spec()
    return OrderBook(floor, OrderBook.initial(floor), lambda: None)


def test_a_heartbeat_that_lags_the_ledger_does_not_refuse_an_order():
    book = _book()  # o2 lies on TU_B, TM_1 carries nothing by the ledger
    stale = [{"id": "TM_1", "online": True, "possesses": ["o2"]}]
    op = book.accept("o2", "TU_C", "TU_B", stale)
    assert book.ops[op]["source"] == "TU_B" and book.carried_by("TM_1") == []


def test_a_module_the_ledger_says_carries_an_object_blocks_a_pick_up():
    book = _book()
    book.move("o5", "TM_1")  # a delivery given up: the object stays on the module
    assert book.carried_by("TM_1") == ["o5"]
    with pytest.raises(OperationRefused, match=r"every transport module carries an object "
                                               r"\(TM_1 carries o5\)"):
        book.accept("o2", "TU_C", None, [{"id": "TM_1", "online": True, "possesses": []}])
    book.locate("o5", "TU_A")  # the operator took it off and says where it is
    assert book.carried_by("TM_1") == []
    assert book.accept("o2", "TU_C", None, [{"id": "TM_1", "online": True}]).startswith("op")


def test_an_object_whose_place_is_unknown_is_carried_by_no_one():
    book = _book()
    book.move("o5", "TM_1")
    book.data["unknown"]["o5"] = {"last_seen": "TM_1", "operation": "op1"}
    assert book.carried_by("TM_1") == []


def test_an_object_left_on_a_module_outside_a_pre_transfer_state_waits_for_an_operator():
    """Seen in the chaos run: o1 rested on TM_1 where no transfer can start; every onward
    order failed at the scan and the floor's one module, carrying it, took no other order."""
    book = _book()
    modules = [{"id": "TM_1", "online": True}]
    op = book.accept("o5", "TU_C", None, modules)
    book.move("o5", "TM_1")  # picked up; the delivery then failed and left it on the module
    book.finish(op, {"status": "failed at delivery", "failed_step": "scanning",
                     "reason": "o5 is not in a pre-transfer state (Eq. 5.7): seen at x ∈ "
                               "[-0.232, -0.011] m"})  # fmt: skip
    with pytest.raises(OperationRefused, match=r"o5 lies on TM_1 outside a pre-transfer state "
                                               rf"\(the scan of {op}\).*cps locate --object o5"):
        book.accept("o5", "TU_D", None, modules)
    book.locate("o5", "TU_A")  # the operator put it on TU_A
    assert book.accept("o5", "TU_D", None, modules).startswith("op")


def test_a_scan_that_fails_for_another_reason_or_at_a_unit_leaves_the_object_orderable():
    book = _book()
    modules = [{"id": "TM_1", "online": True}]
    op = book.accept("o5", "TU_C", None, modules)
    book.move("o5", "TM_1")
    book.finish(op, {"status": "failed at delivery", "failed_step": "scanning",
                     "reason": "target belts occupied: TU_C holds o3"})  # fmt: skip
    again = book.accept("o5", "TU_D", None, modules)  # onward from the module
    book.move("o5", "TU_A")  # (taken back: the pick-up side)
    book.finish(again, {"status": "failed at pick-up", "failed_step": "scanning",
                        "reason": "o5 is not in a pre-transfer state (Eq. 5.7)"})  # fmt: skip
    assert book.accept("o5", "TU_D", None, modules).startswith("op")  # on a unit: put down anew
