"""The result-store contract: `ResultStore`, the stored study plan and `PlanMismatch`.

Every backend passes one conformance suite (``tests/unit/store/test_conformance.py``).

Contract:

- A store holds one study plan (`init_plan`): the first call stores it, later calls
  with the same hash return it, a different hash raises `PlanMismatch`.
- `put` checks a batch of rows, then inserts them in ONE transaction, insert-or-ignore
  by key (the first row with a key wins, later ones are dropped, also within a batch),
  and returns how many rows were actually inserted. A batch with an invalid row
  inserts nothing.
- Reads (`rows`, `done_keys`, `count`, `count_by_status`) return fresh plain Python
  values: mutating them never changes the store.
- `rows` yields rows ordered by key (object_id, face, conveyor by code point; theta_deg,
  run numerically) with exactly `RESULT_COLUMNS` then ``finished_utc``.
- After `close` every method but `close` raises ValueError.
"""

from __future__ import annotations

import json
from abc import ABC, abstractmethod
from collections.abc import Iterator, Mapping, Sequence
from dataclasses import dataclass
from datetime import datetime, timedelta
from types import TracebackType
from typing import Self

from transfertwin._errors import InputError
from transfertwin.store._schema import ResultKey

__all__ = ["PlanMismatch", "ResultStore", "StoredPlan", "check_plan_args", "plan_mismatch"]


class PlanMismatch(InputError):  # noqa: N818 (public API name)
    """The store already holds a different study plan."""


@dataclass(frozen=True)
class StoredPlan:
    """The study plan a store is bound to.

    Attributes:
        plan_hash: Identity of the plan (e.g. a SHA-256 of its canonical JSON).
        plan_json: The plan itself, JSON text.
        created_utc: When the plan was first stored, timezone-aware UTC.
        schema_version: Layout version of the store that holds it.
    """

    plan_hash: str
    plan_json: str
    created_utc: datetime
    schema_version: int

    def __post_init__(self) -> None:
        if self.created_utc.utcoffset() != timedelta(0):
            raise ValueError(f"created_utc must be timezone-aware UTC, got {self.created_utc!r}")


def check_plan_args(plan_hash: object, plan_json: object) -> None:
    """Raise ValueError unless the hash is a non-empty str and the plan is JSON text."""
    if not isinstance(plan_hash, str) or not plan_hash:
        raise ValueError(f"plan_hash must be a non-empty str, got {plan_hash!r}")
    if not isinstance(plan_json, str):
        raise ValueError(f"plan_json must be a str, got {type(plan_json).__name__}")
    try:
        json.loads(plan_json)
    except json.JSONDecodeError as exc:
        raise ValueError(f"plan_json is not valid JSON: {exc}") from None


def plan_mismatch(where: str, stored_hash: str, requested_hash: str) -> PlanMismatch:
    """The one-line error for a store that holds another plan than the one requested."""
    return PlanMismatch(
        f"{where} holds a different study plan (stored {stored_hash[:12]}, requested "
        f"{requested_hash[:12]}); use a new --db or the same options"
    )


class ResultStore(ABC):
    """Abstract result store: one study plan and its experiment results, keyed by
    (object_id, face, conveyor, theta_deg, run). See the module docstring for the contract.
    """

    @abstractmethod
    def init_plan(self, plan_hash: str, plan_json: str) -> StoredPlan:
        """Bind the store to a plan; return the stored plan.

        Raises:
            PlanMismatch: The store already holds a plan with another hash.
            ValueError: An empty hash or a plan that is not JSON text.
        """

    @abstractmethod
    def plan(self) -> StoredPlan | None:
        """The stored plan, or None before `init_plan`."""

    @abstractmethod
    def put(self, rows: Sequence[Mapping[str, object]]) -> int:
        """Insert rows whose key is not stored yet, in one transaction.

        Args:
            rows: Rows with exactly `RESULT_COLUMNS` (``finished_utc`` optional: it is
                added as the commit time when absent).

        Returns:
            The number of rows actually inserted.

        Raises:
            ValueError: A missing or unknown column or a value of the wrong type
                (nothing is inserted then).
        """

    @abstractmethod
    def done_keys(self) -> set[ResultKey]:
        """The keys (object_id, face, conveyor, theta_deg, run) of all stored rows."""

    @abstractmethod
    def count(self) -> int:
        """The number of stored rows."""

    @abstractmethod
    def count_by_status(self) -> dict[str, int]:
        """Stored rows per status: every status of `STATUSES`, in that order, zeros included."""

    @abstractmethod
    def rows(self) -> Iterator[dict[str, object]]:
        """All stored rows ordered by key: `RESULT_COLUMNS` then ``finished_utc``.

        Values are plain Python: None for an undetermined int, ``float('nan')`` for a
        missing float. Do not `put` while iterating.
        """

    @abstractmethod
    def close(self) -> None:
        """Release the store's resources; calling it again does nothing."""

    def __enter__(self) -> Self:
        return self

    def __exit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        tb: TracebackType | None,
    ) -> None:
        self.close()
