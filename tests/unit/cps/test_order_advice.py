"""What the TMS tells the operator after an operation that lost track of its object (found
walking the tutorial by hand: the order said "is at unknown" and nothing more; the TMS then
refused every order of the object until `cps locate`). The advice is a line of the
operation's history, so `cps order`, `cps status` and the console's steps all show it."""

from __future__ import annotations

import pytest

from transfertwin.cps.dispatch import OrderBook
from transfertwin.cps.dispatch._orders import locate_advice
from transfertwin.cps.floor import default_floor_spec
from transfertwin.cps.opcua import OperationRefused

MODULES = [{"id": "TM_1", "online": True}]


def _book() -> OrderBook:
    floor = default_floor_spec()
    return OrderBook(floor, OrderBook.initial(floor), lambda: None)


def test_an_object_the_floor_lost_gets_the_locate_command_in_its_operations_history():
    book = _book()
    op = book.accept("o5", "TU_C", None, MODULES)
    book.move("o5", "TM_1")
    book.finish(op, {"status": "failed while transferring", "location_unknown": True,
                     "reason": "TM_1 went offline (lease expired) while transferring"})  # fmt: skip
    lines = [what for _, what in book.ops[op]["history"]]
    assert lines[-2:] == [locate_advice("o5"), "failed"]
    assert "'transfertwin cps locate --object o5 --at UNIT'" in lines[-2]
    assert lines[-2].endswith("then order it on")
    assert book.ops[op]["location"] == "unknown, last seen at TM_1"
    # what the advice says is what the TMS needs: refused until located, then accepted
    with pytest.raises(OperationRefused, match="cps locate"):
        book.accept("o5", "TU_D", None, MODULES)
    book.locate("o5", "TU_A")
    assert book.accept("o5", "TU_D", None, MODULES).startswith("op")


def test_a_late_result_that_loses_the_object_adds_the_advice_once():
    book = _book()
    op = book.accept("o5", "TU_C", None, MODULES)
    book.move("o5", "TM_1")
    book.finish(op, {"status": "failed while transferring", "reason": "lease expired"})
    assert locate_advice("o5") not in [what for _, what in book.ops[op]["history"]]
    late = {"event": "result", "result": {"status": "failed at delivery",
                                          "location_unknown": True}}  # fmt: skip
    book.progress(op, late)
    book.progress(op, late)  # reported twice (a retry): advised once
    lines = [what for _, what in book.ops[op]["history"]]
    assert lines.count(locate_advice("o5")) == 1


def test_an_object_the_floor_knows_needs_no_advice():
    book = _book()
    op = book.accept("o2", "TU_C", None, MODULES)
    book.move("o2", "TM_1")
    book.move("o2", "TU_C")
    book.finish(op, {"status": "delivered"})
    assert [what for _, what in book.ops[op]["history"]][-1] == "done"
    assert not any("cps locate" in what for _, what in book.ops[op]["history"])
