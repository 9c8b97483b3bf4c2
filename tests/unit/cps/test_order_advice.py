"""What `cps order` tells the operator after an operation that lost track of its object
(found walking the tutorial by hand: the order said "is at unknown" and nothing more; the
TMS then refused every order of the object until `cps locate`)."""

from __future__ import annotations

from transfertwin.cli._cps_floor import next_step


def test_an_object_the_floor_lost_gets_the_locate_command_to_run():
    step = next_step("o3", "unknown, last seen at TM_1 (op10)")
    assert step is not None
    assert "'transfertwin cps locate --object o3 --at UNIT'" in step
    assert "then order it on" in step


def test_an_object_the_floor_knows_needs_no_advice():
    assert next_step("o3", "TU_C") is None
    assert next_step("o3", "TM_1") is None
