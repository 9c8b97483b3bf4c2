"""`MemoryResultStore`: the contract held in a dict; for tests and throw-away studies."""

from __future__ import annotations

from collections.abc import Iterator, Mapping, Sequence
from datetime import UTC, datetime

from transfertwin.store._base import ResultStore, StoredPlan, check_plan_args, plan_mismatch
from transfertwin.store._schema import (
    SCHEMA_VERSION,
    STATUSES,
    ResultKey,
    key_of,
    normalize_row,
    utc_now_iso,
)

__all__ = ["MemoryResultStore"]


class MemoryResultStore(ResultStore):
    """A result store in process memory: same behaviour as the SQLite store, no file.

    Nothing survives the process; not thread-safe.
    """

    def __init__(self) -> None:
        self._rows: dict[ResultKey, dict[str, object]] = {}
        self._plan: StoredPlan | None = None
        self._closed = False

    def __repr__(self) -> str:
        return f"MemoryResultStore(rows={len(self._rows)})"

    def _check_open(self) -> None:
        if self._closed:
            raise ValueError("operation on a closed in-memory result store")

    def init_plan(self, plan_hash: str, plan_json: str) -> StoredPlan:
        """Bind the store to a plan (see `ResultStore.init_plan`)."""
        self._check_open()
        check_plan_args(plan_hash, plan_json)
        if self._plan is None:
            self._plan = StoredPlan(plan_hash, plan_json, datetime.now(UTC), SCHEMA_VERSION)
        elif self._plan.plan_hash != plan_hash:
            raise plan_mismatch("the in-memory store", self._plan.plan_hash, plan_hash)
        return self._plan

    def plan(self) -> StoredPlan | None:
        """The stored plan, or None (see `ResultStore.plan`)."""
        self._check_open()
        return self._plan

    def put(self, rows: Sequence[Mapping[str, object]]) -> int:
        """Insert-or-ignore rows by key, all or nothing (see `ResultStore.put`)."""
        self._check_open()
        if isinstance(rows, Mapping):
            raise ValueError("put() takes a sequence of rows, got a single mapping")
        now = utc_now_iso()
        batch = [normalize_row(row, now) for row in rows]
        inserted = 0
        for row in batch:
            key = key_of(row)
            if key not in self._rows:
                self._rows[key] = row
                inserted += 1
        return inserted

    def done_keys(self) -> set[ResultKey]:
        """The keys of all stored rows."""
        self._check_open()
        return set(self._rows)

    def count(self) -> int:
        """The number of stored rows."""
        self._check_open()
        return len(self._rows)

    def count_by_status(self) -> dict[str, int]:
        """Stored rows per status, every status included."""
        self._check_open()
        counts = dict.fromkeys(STATUSES, 0)
        for row in self._rows.values():
            counts[row["status"]] += 1  # type: ignore[index]
        return counts

    def rows(self) -> Iterator[dict[str, object]]:
        """Copies of all stored rows ordered by key."""
        self._check_open()
        snapshot = self._rows
        return (dict(snapshot[key]) for key in sorted(snapshot))

    def close(self) -> None:
        """Mark the store closed; the rows are dropped."""
        self._closed = True
        self._rows = {}
