"""The TMS's object ledger: impossible orders are refused with the reason, one object
cannot be reserved twice, completed transfers move it."""

from __future__ import annotations

import threading

import pytest

from transfertwin._errors import InputError
from transfertwin.cps.aas import DEMO_OBJECTS, DEMO_PLACEMENT
from transfertwin.cps.apps import ObjectLedger
from transfertwin.cps.opcua import OperationRefused

UNITS = ("TU_A", "TU_B", "TU_C", "TU_D")


def _ledger() -> ObjectLedger:
    return ObjectLedger(DEMO_PLACEMENT, UNITS)


def test_demo_placement_puts_every_object_on_a_unit():
    assert set(DEMO_PLACEMENT) == set(DEMO_OBJECTS)
    assert set(DEMO_PLACEMENT.values()) <= set(UNITS)
    assert DEMO_PLACEMENT["o5"] == "TU_A"  # the README's order starts there


@pytest.mark.parametrize(
    ("source", "target", "obj", "status", "argument", "reason"),
    [
        ("TU_A", "TU_Z", "o5", "BadInvalidArgument", "target", "no transfer unit 'TU_Z'"),
        ("TM_1", "TU_C", "o5", "BadInvalidArgument", "source", "no transfer unit 'TM_1'"),
        ("TU_A", "TU_C", "o99", "BadInvalidArgument", "object", "'o99' is not an object"),
        ("TU_B", "TU_B", "o2", "BadInvalidArgument", "target", "both TU_B"),
        ("TU_B", "TU_C", "o5", "BadInvalidState", "source", "o5 is at TU_A, not at TU_B"),
    ],
)
def test_impossible_orders_are_refused_with_the_reason(source, target, obj, status, argument,
                                                        reason):  # fmt: skip
    ledger = _ledger()
    with pytest.raises(OperationRefused) as refused:
        ledger.reserve("op1", source, target, obj)
    assert refused.value.status == status
    assert refused.value.argument == argument
    assert reason in refused.value.reason
    assert ledger.moving() == {} and ledger.locations() == dict(sorted(DEMO_PLACEMENT.items()))


def test_an_object_is_reserved_once_and_moves_with_each_transfer():
    ledger = _ledger()
    ledger.reserve("op1", "TU_A", "TU_C", "o5")
    with pytest.raises(OperationRefused, match="being moved by op1"):
        ledger.reserve("op2", "TU_A", "TU_D", "o5")
    ledger.reserve("op3", "TU_A", "TU_D", "o1")  # another object on the same unit is free
    assert ledger.move("o5", "TM_1") == "TU_A"
    assert ledger.move("o5", "TU_C") == "TM_1"
    ledger.release("op1", "o5")
    assert ledger.location("o5") == "TU_C"
    assert ledger.objects_at("TU_C") == ["o3", "o5"]
    with pytest.raises(OperationRefused, match="o5 is at TU_C, not at TU_A"):
        ledger.reserve("op4", "TU_A", "TU_C", "o5")
    ledger.reserve("op4", "TU_C", "TU_A", "o5")
    ledger.release("op1", "o5")  # not its holder: no effect
    assert ledger.moving() == {"o1": "op3", "o5": "op4"}


def test_concurrent_orders_for_one_object_cannot_both_win():
    ledger = _ledger()
    start = threading.Barrier(8)
    won, refused = [], []

    def order(i: int) -> None:
        start.wait()
        try:
            ledger.reserve(f"op{i}", "TU_A", "TU_C" if i % 2 else "TU_D", "o5")
            won.append(i)
        except OperationRefused as exc:
            refused.append(exc.reason)

    threads = [threading.Thread(target=order, args=(i,)) for i in range(8)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert len(won) == 1 and len(refused) == 7
    assert all(r == f"o5 is being moved by op{won[0]}" for r in refused)


def test_initial_locations_must_be_transfer_units():
    with pytest.raises(InputError, match="o1: initial location 'TM_1'"):
        ObjectLedger({"o1": "TM_1"}, UNITS)
