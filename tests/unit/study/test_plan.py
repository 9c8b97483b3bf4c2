"""Study plans: sizes, seeds, identity (Sec. 6.6, Eq. 6.20)."""

from __future__ import annotations

import itertools

import pytest

from transfertwin import InputError
from transfertwin.sim import DockingError, SceneConfig
from transfertwin.study import (
    PRESETS,
    FixedDockingError,
    ResampledDockingErrors,
    StudyPlan,
    experiment_seeds,
    parse_objects,
)


def _plan(**kw) -> StudyPlan:
    base = {"objects": ("o1", "o2"), "theta_step": 30, "runs": 3, "seed": 5,
            "docking": FixedDockingError()}  # fmt: skip
    base.update(kw)
    return StudyPlan(**base)


def test_eq_6_20_full_preset_is_the_studys_1709400_experiments():
    full = PRESETS["full"]
    plan = StudyPlan(full.objects, full.theta_step, full.runs, 0, FixedDockingError())
    assert plan.n_experiments == 37 * 924 * 50 == 1_709_400


def test_theta_step_30_plans_28_states_per_object():
    plan = _plan()
    assert len(plan.states()) == 28
    assert plan.n_experiments == 2 * 28 * 3


def test_plan_hash_is_stable_and_sensitive():
    assert _plan().plan_hash == _plan().plan_hash
    assert _plan().plan_hash != _plan(runs=4).plan_hash
    assert _plan().plan_hash != _plan(scene=SceneConfig(mu=0.3)).plan_hash
    assert _plan().plan_hash != _plan(seed=6).plan_hash


def test_plan_of_built_in_cores_records_their_shipped_features(monkeypatch):
    from transfertwin.objects import features_version

    plan = _plan()
    before = plan.plan_hash
    assert plan.describe()["core_features"] == features_version() != "none"
    assert _plan(objects=("/data/part.stl",)).describe()["core_features"] is None
    monkeypatch.setattr("transfertwin.study.experiment._plan.features_version", lambda: "other")
    assert _plan().plan_hash != before  # other features: the store is not resumed


def test_plan_json_round_trips():
    plan = _plan(docking=ResampledDockingErrors.from_csv(), scene=SceneConfig(gap_m=0.02))
    again = StudyPlan.from_json(plan.to_json())
    assert again.plan_hash == plan.plan_hash
    assert again.scene == plan.scene


def test_seeds_depend_only_on_master_object_state_and_run():
    a = experiment_seeds(0, "o1", 10, 3)
    assert a == experiment_seeds(0, "o1", 10, 3)
    others = {experiment_seeds(0, "o2", 10, 3), experiment_seeds(0, "o1", 11, 3),
              experiment_seeds(0, "o1", 10, 4), experiment_seeds(1, "o1", 10, 3)}  # fmt: skip
    assert a not in others and len(others) == 4
    assert a[0] != a[1]  # experiment and docking seeds differ


def test_specs_cover_every_key_once_with_per_run_docking_errors():
    plan = _plan(docking=ResampledDockingErrors.from_csv())
    items = list(plan.specs({"o1": "o1", "o2": "o2"}))
    keys = [k for k, _ in items]
    assert len(keys) == len(set(keys)) == plan.n_experiments
    errors = {spec.docking_error for _, spec in items}
    assert len(errors) > 20  # resampled per experiment, not one per study


def test_resampled_errors_come_from_the_real_measurements():
    model = ResampledDockingErrors.from_csv()
    assert len(model.errors_mm_deg) == 191
    err = model.sample(123)
    assert err == model.sample(123)
    assert tuple(round(v, 6) for v in err.as_mm_deg()) in {
        tuple(round(v, 6) for v in row) for row in model.errors_mm_deg
    }


def test_fixed_error_ignores_the_seed():
    e = DockingError.from_mm_deg(-5, 3, 1)
    assert FixedDockingError(e).sample(1) == FixedDockingError(e).sample(2) == e


@pytest.mark.parametrize("bad", ["", "o0", "o1,o1", "nope.stl"])
def test_parse_objects_rejects_bad_lists(bad):
    with pytest.raises(InputError):
        parse_objects(bad)


def test_parse_objects_all_is_the_37_cores():
    assert parse_objects("all") == tuple(f"o{i}" for i in range(1, 38))


@pytest.mark.parametrize("kw", [{"runs": 0}, {"theta_step": 0}, {"seed": -1}, {"objects": ()}])
def test_invalid_plans_are_input_errors(kw):
    with pytest.raises(InputError):
        _plan(**kw)


@pytest.mark.parametrize("step", [7, 25, 361])
def test_a_theta_step_that_does_not_divide_360_is_refused_naming_the_divisors(step):
    with pytest.raises(InputError, match=r"--theta-step must divide 360 .*\b45\b.*got"):
        _plan(theta_step=step)


@pytest.mark.parametrize("step", [1, 5, 30, 45, 90, 360])
def test_every_divisor_of_360_makes_an_even_grid(step):
    thetas = sorted({s.theta_deg for s in _plan(theta_step=step).states()})
    assert len(thetas) == 360 // step
    assert {b - a for a, b in itertools.pairwise(thetas)} <= {step}


def test_plan_with_the_default_copula_round_trips_and_resumes_identically():
    from transfertwin.study import GaussianCopula, measured_docking_errors

    plan = _plan(docking=GaussianCopula.fit(measured_docking_errors()))
    again = StudyPlan.from_json(plan.to_json())
    assert again.plan_hash == plan.plan_hash
    refitted = _plan(docking=GaussianCopula.fit(measured_docking_errors()))
    assert refitted.plan_hash == plan.plan_hash  # the fit is deterministic: resume works
    ids = {"o1": "o1", "o2": "o2"}
    first = [s.docking_error for _, s in plan.specs(ids)][:5]
    assert first == [s.docking_error for _, s in again.specs(ids)][:5]


def test_specs_skip_done_keys_without_changing_the_others():
    plan = _plan()
    ids = {"o1": "o1", "o2": "o2"}
    keys = list(plan.keys(ids))
    done = set(keys[::3])
    rest = dict(plan.specs(ids, done))
    assert set(rest) == set(keys) - done
    full = dict(plan.specs(ids))
    assert all(rest[k] == full[k] for k in rest)


def test_a_plan_of_chosen_states_runs_those_only_and_keeps_other_hashes():
    plain = _plan()
    assert "states" not in plain.describe()  # hashes of plans without a choice unchanged
    only = (("back", "right", 180), ("front", "left", 0))
    plan = _plan(only_states=only)
    assert [(s.face, s.conveyor, s.theta_deg) for s in plan.states()] == list(only)
    assert plan.n_experiments == 2 * 2 * 3
    assert plan.plan_hash != plain.plan_hash
    again = StudyPlan.from_json(plan.to_json())
    assert again.plan_hash == plan.plan_hash and again.states() == plan.states()
    with pytest.raises(InputError, match="twice"):
        _plan(only_states=(only[0], only[0]))
    with pytest.raises(InputError):
        _plan(only_states=(("side", "left", 0),))


def test_a_plan_of_operation_legs_draws_a_delivery_docking_error_and_keeps_other_hashes():
    from transfertwin.study.docking import docking_model

    plain = _plan(docking=docking_model("copula"))
    assert "leg" not in plain.describe()  # round-trip plans keep their hashes
    plan = _plan(docking=docking_model("copula"), leg="operation")
    assert plan.describe()["leg"] == "operation" and plan.plan_hash != plain.plan_hash
    assert StudyPlan.from_json(plan.to_json()).plan_hash == plan.plan_hash
    ids = {"o1": "o1", "o2": "o2"}
    for (_, a), (_, b) in zip(plain.specs(ids), plan.specs(ids), strict=True):
        assert (a.leg, b.leg) == ("round-trip", "operation")
        # the same pick-up draws as the round trip's; the delivery's error is its own
        assert (a.seed, a.docking_error) == (b.seed, b.docking_error)
        assert a.delivery_docking_error is None
        assert b.delivery_docking_error not in (None, b.docking_error)
    with pytest.raises(InputError, match="--leg"):
        _plan(leg="there")
