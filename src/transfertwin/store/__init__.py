"""Result store: one row per experiment, committed as it completes.

The contract is `ResultStore` (``_base.py``): a study plan bound to the store
(`init_plan`, `PlanMismatch` for another plan), insert-or-ignore `put` by key
(object_id, face, conveyor, theta_deg, run) in one transaction, and reads that
return plain Python values. `SQLiteResultStore` is the default backend (WAL, one
committed transaction per put, safe against SIGKILL; one writer process, many
readers); `MemoryResultStore` holds the same contract in memory. Tables leave and
enter as CSV or Parquet (`export_results`, `read_results`). Schema version
`SCHEMA_VERSION`; timestamps are timezone-aware UTC.

This layer imports only the standard library, pyarrow and `transfertwin._errors`.
"""

from transfertwin.store._base import PlanMismatch, ResultStore, StoredPlan
from transfertwin.store._export import EXPORT_SUFFIXES, export_results
from transfertwin.store._memory import MemoryResultStore
from transfertwin.store._read import REQUIRED_COLUMNS, SQLITE_SUFFIXES, read_results
from transfertwin.store._schema import (
    COLUMN_TYPES,
    DOCKING_ERROR_COLUMNS,
    FINISHED_COLUMN,
    KEY_COLUMNS,
    NULLABLE_INT_COLUMNS,
    RESULT_COLUMNS,
    SCHEMA_VERSION,
    STATUSES,
    ResultKey,
)
from transfertwin.store._sqlite import SQLiteResultStore

__all__ = [
    "COLUMN_TYPES",
    "DOCKING_ERROR_COLUMNS",
    "EXPORT_SUFFIXES",
    "FINISHED_COLUMN",
    "KEY_COLUMNS",
    "NULLABLE_INT_COLUMNS",
    "REQUIRED_COLUMNS",
    "RESULT_COLUMNS",
    "SCHEMA_VERSION",
    "SQLITE_SUFFIXES",
    "STATUSES",
    "MemoryResultStore",
    "PlanMismatch",
    "ResultKey",
    "ResultStore",
    "SQLiteResultStore",
    "StoredPlan",
    "export_results",
    "read_results",
]
