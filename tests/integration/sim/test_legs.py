"""The legs of a floor's transport operation as E^V: a pick-up from the unit onto the
module, and the whole operation (pick-up, then delivery at another unit)."""

from __future__ import annotations

import pytest

from transfertwin import InputError
from transfertwin.sim import DockingError, SceneConfig
from transfertwin.study import ExperimentSpec, run_experiment


def _spec(box_stl, **kw) -> ExperimentSpec:
    base = {"face": "front", "conveyor": "both", "theta_deg": 0, "units": "mm"}
    base.update(kw)
    return ExperimentSpec(str(box_stl), **base)


def test_a_pick_up_starts_on_the_unit_and_ends_on_the_module(box_stl):
    r = run_experiment(_spec(box_stl, leg="pick-up", record=True))
    assert (r.status, r.y1, r.y2, r.success) == ("ok", 1, None, 1)
    assert r.state_pre[0] == 1 and r.state_end_1[0] == 0  # possession TU, then TM
    assert r.state_pre[1] > 0 > r.state_end_1[1]  # it crossed the gap towards the module
    assert {f.phase for f in r.frames} == {"pick-up"}


def test_an_operation_delivers_from_where_the_pick_up_left_it(box_stl):
    there = DockingError.from_mm_deg(2.0, 1.0, 0.5)
    r = run_experiment(
        _spec(
            box_stl,
            leg="operation",
            record=True,
            docking_error=there,
            delivery_docking_error=DockingError.from_mm_deg(-3, -2, -1),
        )
    )
    assert (r.status, r.y1, r.y2, r.success) == ("ok", 1, 1, 1)
    assert r.state_pre[0] == 1 and r.state_end_1[0] == 0 and r.state_end_2[0] == 1
    assert r.frames[0].phase == "pick-up"
    assert r.frames[-1].phase == "delivery"
    assert r.frames[-1].t_s == round(r.t_end_s, 6)


def test_a_failed_pick_up_ends_the_operation(box_stl):
    r = run_experiment(_spec(box_stl, leg="operation", scene=SceneConfig(mu=0.0, t_max_s=3.0)))
    assert (r.status, r.y1, r.y2, r.success) == ("ok", 0, None, 0)


def test_the_legs_of_a_core_differ_from_its_round_trip():
    """o1 on its back at θ = 0 is not picked up (it catches in the gap coming off the
    unit), while o23 is: the pick-up is a prediction of its own, not the round trip's."""
    err = DockingError.from_mm_deg(3.0, 1.0, 0.5)
    got = {obj: run_experiment(ExperimentSpec(obj, "back", "both", 0, docking_error=err,
                                              seed=1, leg="pick-up")).y1
           for obj in ("o1", "o23")}  # fmt: skip
    assert got == {"o1": 0, "o23": 1}


def test_bad_legs_are_input_errors(box_stl):
    with pytest.raises(InputError, match="leg must be one of"):
        _spec(box_stl, leg="back")
    with pytest.raises(InputError, match="round-trip' only"):
        run_experiment(_spec(box_stl, leg="pick-up"), sensor="perception")
