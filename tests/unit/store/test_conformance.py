"""The result-store contract (docs/architecture.md, "Contracts"): every backend passes this
one suite."""

from __future__ import annotations

import dataclasses
import math
import random
from collections.abc import Callable, Iterator
from datetime import UTC, datetime, timedelta
from pathlib import Path

import numpy as np
import pytest

from tests.unit.store.rows import assert_rows_equal, result_row, sort_key, tricky_rows
from transfertwin import InputError
from transfertwin.store import (
    FINISHED_COLUMN,
    RESULT_COLUMNS,
    SCHEMA_VERSION,
    STATUSES,
    MemoryResultStore,
    PlanMismatch,
    ResultStore,
    SQLiteResultStore,
    StoredPlan,
)

BACKENDS: dict[str, Callable[[Path], ResultStore]] = {
    "memory": lambda _tmp: MemoryResultStore(),
    "sqlite": lambda tmp: SQLiteResultStore(tmp / "results.sqlite"),
}


@pytest.fixture(params=sorted(BACKENDS))
def make_store(
    request: pytest.FixtureRequest, tmp_path: Path
) -> Iterator[Callable[[], ResultStore]]:
    """A factory of fresh stores of one backend (each in its own folder); all closed after."""
    opened: list[ResultStore] = []

    def make() -> ResultStore:
        folder = tmp_path / f"db{len(opened)}"
        folder.mkdir()
        opened.append(BACKENDS[request.param](folder))
        return opened[-1]

    yield make
    for store in opened:
        store.close()


@pytest.fixture
def store(make_store: Callable[[], ResultStore]) -> ResultStore:
    return make_store()


def stored(store: ResultStore) -> list[dict[str, object]]:
    """Stored rows without the commit time."""
    return [{k: v for k, v in row.items() if k != FINISHED_COLUMN} for row in store.rows()]


def test_backend_is_a_result_store(store: ResultStore) -> None:
    assert isinstance(store, ResultStore)


def test_new_store_is_empty(store: ResultStore) -> None:
    assert store.count() == 0
    assert store.done_keys() == set()
    assert list(store.rows()) == []
    assert store.plan() is None
    assert store.count_by_status() == dict.fromkeys(STATUSES, 0)


def test_put_inserts_a_key_once_and_returns_inserted_count(store: ResultStore) -> None:
    a, b, c = result_row(run=0), result_row(run=1), result_row(run=2)
    assert store.put([a, b]) == 2
    assert store.put([a]) == 0
    assert store.put([b, c]) == 1
    assert store.count() == 3


def test_first_row_with_a_key_wins_also_within_a_batch(store: ResultStore) -> None:
    first, second = result_row(message="first"), result_row(message="second", status="error")
    assert store.put([first, second]) == 1
    assert store.put([result_row(message="third")]) == 0
    assert stored(store) == [first]


def test_put_of_nothing_inserts_nothing(store: ResultStore) -> None:
    assert store.put([]) == 0
    assert store.count() == 0


def test_done_keys_are_typed_key_tuples(store: ResultStore) -> None:
    store.put([result_row("o2", "back", "both", -7, 3), result_row("o1", "front", "left", 0, 0)])
    keys = store.done_keys()
    assert keys == {("o2", "back", "both", -7, 3), ("o1", "front", "left", 0, 0)}
    assert all(type(k[3]) is int and type(k[4]) is int for k in keys)


def test_count_by_status_lists_every_status_in_order(store: ResultStore) -> None:
    store.put([result_row(run=i, status=s) for i, s in enumerate(["ok", "error", "ok", "invalid"])])
    counts = store.count_by_status()
    assert list(counts) == list(STATUSES)
    assert counts == {"ok": 2, "invalid": 1, "unstable": 0, "error": 1}


def test_rows_come_ordered_by_key(store: ResultStore) -> None:
    keys = [
        ("o1", "front", "left", theta, run) for theta in (-179, -5, 0, 10, 180) for run in (2, 10)
    ] + [("o10", "back", "both", 0, 0), ("o2", "back", "right", 0, 0)]
    rows = [result_row(*key) for key in keys]
    random.Random(1).shuffle(rows)
    store.put(rows)
    assert [sort_key(row) for row in store.rows()] == sorted(keys)


def test_rows_round_trip_exactly(store: ResultStore) -> None:
    rows = tricky_rows()
    assert store.put(rows) == len(rows)
    assert_rows_equal(stored(store), sorted(rows, key=sort_key))


def test_rows_have_result_columns_then_finished_utc(store: ResultStore) -> None:
    store.put([result_row()])
    (row,) = store.rows()
    assert tuple(row) == (*RESULT_COLUMNS, FINISHED_COLUMN)


def test_finished_utc_is_timezone_aware_utc_commit_time(store: ResultStore) -> None:
    before = datetime.now(UTC)
    store.put([result_row()])
    after = datetime.now(UTC)
    (row,) = store.rows()
    finished = datetime.fromisoformat(str(row[FINISHED_COLUMN]))
    assert finished.utcoffset() == timedelta(0)
    assert before - timedelta(seconds=1) <= finished <= after + timedelta(seconds=1)


def test_rows_copied_between_stores_keep_finished_utc(
    make_store: Callable[[], ResultStore],
) -> None:
    source, target = make_store(), make_store()
    source.put(tricky_rows())
    assert target.put(list(source.rows())) == len(tricky_rows())
    assert_rows_equal(list(target.rows()), list(source.rows()))


def test_numpy_scalars_and_none_become_plain_python(store: ResultStore) -> None:
    store.put(
        [
            result_row(
                theta_deg=np.int16(-3), run=np.int64(1), seed=np.uint32(9), y1=np.int8(0),
                dock_err_x_mm=np.float32(0.5), dock_err_y_mm=np.float64(-1.25), t_end_s=None,
                message=None, state_end_2=None, success=True,
            )
        ]
    )  # fmt: skip
    (row,) = stored(store)
    assert (type(row["theta_deg"]), type(row["run"]), type(row["seed"])) == (int, int, int)
    assert (row["theta_deg"], row["run"], row["seed"], row["y1"]) == (-3, 1, 9, 0)
    assert type(row["success"]) is int and row["success"] == 1
    assert type(row["dock_err_x_mm"]) is float and row["dock_err_x_mm"] == 0.5
    assert math.isnan(row["t_end_s"])
    assert (row["message"], row["state_end_2"]) == ("", "")


def test_negative_zero_is_stored_as_zero(store: ResultStore) -> None:
    store.put([result_row(dock_err_y_mm=-0.0)])
    (row,) = store.rows()
    assert math.copysign(1.0, row["dock_err_y_mm"]) == 1.0


def test_returned_rows_and_keys_are_copies(store: ResultStore) -> None:
    store.put([result_row()])
    next(store.rows())["status"] = "error"
    store.done_keys().clear()
    assert store.count_by_status()["ok"] == 1
    assert len(store.done_keys()) == 1


BAD_CELLS = {
    "missing column": {"drop": "seed"},
    "unknown column": {"extra": 1},
    "unknown status": {"status": "fine"},
    "empty object_id": {"object_id": ""},
    "text for int": {"theta_deg": "10"},
    "float for int": {"y1": 1.0},
    "None for required int": {"seed": None},
    "int above int64": {"seed": 2**63},
    "text for float": {"t_end_s": "1.5"},
    "None for key text": {"face": None},
}


@pytest.mark.parametrize("case", list(BAD_CELLS))
def test_invalid_row_is_a_programming_error_and_inserts_nothing(
    store: ResultStore, case: str
) -> None:
    bad = {**result_row(run=1), **BAD_CELLS[case]}
    bad.pop("drop", None)
    bad.pop(BAD_CELLS[case].get("drop", ""), None)
    with pytest.raises(ValueError) as info:
        store.put([result_row(run=0), bad, result_row(run=2)])
    assert not isinstance(info.value, InputError)
    assert store.count() == 0


def test_put_refuses_a_single_mapping(store: ResultStore) -> None:
    with pytest.raises(ValueError, match="sequence of rows"):
        store.put(result_row())  # type: ignore[arg-type]


def test_init_plan_stores_the_plan(store: ResultStore) -> None:
    before = datetime.now(UTC)
    plan = store.init_plan("hash-a", '{"objects": ["o1"]}')
    assert (plan.plan_hash, plan.plan_json) == ("hash-a", '{"objects": ["o1"]}')
    assert plan.schema_version == SCHEMA_VERSION
    assert plan.created_utc.utcoffset() == timedelta(0)
    assert before - timedelta(seconds=1) <= plan.created_utc <= datetime.now(UTC)
    assert store.plan() == plan


def test_same_plan_again_returns_the_stored_plan(store: ResultStore) -> None:
    first = store.init_plan("hash-a", '{"a": 1}')
    store.put([result_row()])
    assert store.init_plan("hash-a", '{"a": 1}') == first
    assert store.plan() == first
    assert store.count() == 1


def test_other_plan_raises_plan_mismatch_and_keeps_the_stored_one(store: ResultStore) -> None:
    first = store.init_plan("a" * 64, "{}")
    with pytest.raises(PlanMismatch) as info:
        store.init_plan("b" * 64, "{}")
    message = str(info.value)
    assert isinstance(info.value, InputError)
    assert "\n" not in message
    assert "different study plan" in message and "--db" in message
    assert "a" * 12 in message and "b" * 12 in message
    assert store.plan() == first


@pytest.mark.parametrize(("plan_hash", "plan_json"), [("", "{}"), ("h", "{not json"), ("h", None)])
def test_init_plan_rejects_bad_arguments(
    store: ResultStore, plan_hash: str, plan_json: str
) -> None:
    with pytest.raises(ValueError):
        store.init_plan(plan_hash, plan_json)
    assert store.plan() is None


def test_stored_plan_is_frozen_and_utc() -> None:
    plan = StoredPlan("h", "{}", datetime.now(UTC), SCHEMA_VERSION)
    with pytest.raises(dataclasses.FrozenInstanceError):
        plan.plan_hash = "other"  # type: ignore[misc]
    with pytest.raises(ValueError, match="UTC"):
        StoredPlan("h", "{}", datetime.now(), SCHEMA_VERSION)


def test_closed_store_refuses_work_and_closes_twice(store: ResultStore) -> None:
    with store as same:
        assert same is store
        store.put([result_row()])
    store.close()
    for call in (store.count, store.done_keys, store.plan, store.rows, store.count_by_status):
        with pytest.raises(ValueError, match="closed"):
            call()
    with pytest.raises(ValueError, match="closed"):
        store.put([result_row(run=1)])
