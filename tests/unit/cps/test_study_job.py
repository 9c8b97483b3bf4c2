"""Studies the Experiment Manager runs (issue 28, item 5): the JSON plan is checked before
anything runs, a job stops between experiments and a new job on the same store resumes
it with the same rows an uninterrupted study stores."""

from __future__ import annotations

import json

import pytest

from transfertwin import InputError
from transfertwin.cps.apps import StudyJob, StudyRequest, record_store, study_stores
from transfertwin.store import SQLiteResultStore

TINY = {"objects": ["o1"], "states": [["front", "left", 0], {"face": "back",
        "conveyor": "both", "theta_deg": 90}], "runs": 2, "seed": 3,
        "docking": {"fixed": [1.0, -2.0, 0.5]}}  # fmt: skip


def _request(**changes) -> StudyRequest:
    return StudyRequest.parse(json.dumps(TINY | changes))


def test_a_plan_names_its_states_runs_and_executor():
    req = _request()
    assert req.plan.n_experiments == 1 * 2 * 2
    assert [(s.face, s.conveyor, s.theta_deg) for s in req.plan.states()] == [
        ("front", "left", 0), ("back", "both", 90)]  # fmt: skip
    assert (req.executor, req.workers, req.store) == ("local", 1, None)
    ray = _request(executor="ray", workers=2, chunk_size=3, store="/tmp/x.sqlite")
    assert (ray.executor, ray.workers, ray.chunk_size, str(ray.store)) == (
        "ray", 2, 3, "/tmp/x.sqlite")  # fmt: skip
    step = StudyRequest.parse(json.dumps({"objects": "o1", "theta_step": 90, "runs": 1,
                                          "docking": "resample"}))
    assert step.plan.n_experiments == len(step.plan.states()) > 2
    legs = _request(leg="operation")  # the EM plans a floor's operation E^V as well
    assert legs.plan.leg == "operation" and legs.plan.plan_hash != _request().plan.plan_hash


@pytest.mark.parametrize(("changes", "message"), [
    ({"runz": 2}, "unknown key"),
    ({"runs": 0}, "'runs' must be an integer >= 1"),
    ({"runs": None}, "'runs' is missing"),
    ({"theta_step": 30}, "not both"),
    ({"states": [["front", "left", 7.5]]}, "each state"),
    ({"states": [["side", "left", 0]]}, "face"),
    ({"states": [["back", "right", 90]]}, "not a pre-transfer state of the experiments"),
    ({"objects": ["o99"]}, "unknown object"),
    ({"executor": "slurm"}, "local or ray"),
    ({"address": "auto"}, "needs executor ray"),
    ({"docking": {"fixed": [1, 2]}}, "fixed"),
    ({"leg": "there"}, "--leg must be one of"),
])  # fmt: skip
def test_a_bad_plan_is_refused_with_the_reason(changes, message):
    d = {k: v for k, v in (TINY | changes).items() if v is not None}
    with pytest.raises(InputError, match=message):
        StudyRequest.parse(json.dumps(d))


def test_not_json_is_refused():
    with pytest.raises(InputError, match="not JSON"):
        StudyRequest.parse("{objects: o1}")


def test_a_study_runs_stops_and_resumes_with_the_rows_of_an_uninterrupted_one(tmp_path):
    req = _request(runs=3)  # 6 experiments
    whole = StudyJob(req, tmp_path / "whole.sqlite", own_process=False)
    whole.check_store()
    final = whole.run()
    assert (final["state"], final["done"], final["planned"]) == ("finished", 6, 6)
    assert final["eta_s"] == 0.0 and final["rate_per_s"] > 0

    seen: list[dict] = []

    def stop_after_two(status: dict) -> None:
        seen.append(status)
        if status["done"] >= 2:
            job.stop()

    job = StudyJob(req, tmp_path / "parts.sqlite", on_update=stop_after_two, own_process=False)
    job.check_store()
    first = job.run()
    assert first["state"] == "stopped" and 2 <= first["done"] < 6, first
    assert any(s["state"] == "running" and s["eta_s"] is not None for s in seen)
    again = StudyJob(req, tmp_path / "parts.sqlite", own_process=False)
    again.check_store()
    second = again.run()
    assert (second["state"], second["done"], second["ran"]) == ("finished", 6, 6 - first["done"])

    def rows(name: str) -> list[tuple]:
        with SQLiteResultStore(tmp_path / name, create=False) as store:
            keep = ("object_id", "face", "theta_deg", "run", "seed", "success", "t_end_s")
            return sorted(tuple(r.get(k) for k in keep) for r in store.rows())

    assert rows("parts.sqlite") == rows("whole.sqlite")  # same seeds, same results


def test_a_store_of_another_plan_is_refused_before_anything_runs(tmp_path):
    store = tmp_path / "s.sqlite"
    StudyJob(_request(), store).check_store()
    with pytest.raises(InputError):
        StudyJob(_request(seed=4), store).check_store()
    with SQLiteResultStore(store, create=False) as s:
        assert s.count() == 0


def test_the_manager_lists_its_stores_for_the_console(tmp_path):
    state = tmp_path / "w" / "assets" / "EM" / "state"
    a, b = tmp_path / "a.sqlite", tmp_path / "b.sqlite"
    StudyJob(_request(), a).check_store()
    record_store(state, a)
    record_store(state, b)
    record_store(state, a)  # once only
    assert json.loads((state / "study-stores.json").read_text())["stores"] == [str(a), str(b)]
    assert study_stores(tmp_path / "w") == [a]  # b does not exist (yet)
