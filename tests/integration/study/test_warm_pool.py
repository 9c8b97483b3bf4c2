"""A pool of worker processes kept warm between studies (`WarmPool`, the Experiment
Manager's predictions): the same rows as the study's own workers, study after study."""

from __future__ import annotations

import json

import pytest

from transfertwin import InputError
from transfertwin.store import MemoryResultStore
from transfertwin.study.docking import docking_model
from transfertwin.study.experiment import StudyPlan, WarmPool, run_study


def _rows(plan: StudyPlan, **kw) -> list[str]:
    """The study's rows as JSON (NaN compares equal there), in key order, without the
    time each was stored."""
    store = MemoryResultStore()
    run_study(plan, store, **kw)
    key = ("object_id", "face", "conveyor", "theta_deg", "run")
    rows = sorted(store.rows(), key=lambda r: tuple(r[k] for k in key))
    return [json.dumps({k: v for k, v in r.items() if k != "finished_utc"}) for r in rows]


def test_a_warm_pool_gives_the_rows_of_the_studys_own_workers_and_stays_up() -> None:
    plans = [StudyPlan((obj,), 180, 1, 5, docking_model("copula"), leg="operation")
             for obj in ("o23", "o1")]  # fmt: skip
    with WarmPool(2) as pool:
        first = [_rows(p, executor=pool) for p in plans]
        pids = set(pool._pool._processes)  # the same processes served both studies
        again = _rows(plans[0], executor=pool)
        assert set(pool._pool._processes) == pids
    assert first == [_rows(p) for p in plans]  # in this process: the same bits
    assert again == first[0]
    assert {json.loads(r)["status"] for rows in first for r in rows} == {"ok"}
    with pytest.raises(InputError, match="at least 1"):
        WarmPool(0)


def test_a_pool_that_was_shut_down_is_started_anew() -> None:
    """A pool whose processes were shut down (or broke) under it takes the next study on
    new ones instead of failing with 'cannot schedule new futures after shutdown'."""
    plan = StudyPlan(("o23",), 180, 1, 5, docking_model("copula"), leg="pick-up")
    with WarmPool(1) as pool:
        pool._pool.shutdown(wait=True)
        assert _rows(plan, executor=pool) == _rows(plan)
