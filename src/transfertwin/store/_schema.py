"""The results table: columns, types, key, statuses and the row check every store applies.

One row per experiment (docs/architecture.md, "Contracts"). A row is keyed by
(object_id, face, conveyor, theta_deg, run); a store holds each key at most once.

Column types, as stored and as read back:

- ``"str"``: never NULL. Key columns and ``status`` must be non-empty;
  ``message`` and ``state_*`` accept None, stored as ``""``.
- ``"int"``: 64-bit signed. ``theta_deg``, ``run`` and ``seed`` are required;
  ``y1``, ``y2`` and ``success`` may be None (not determined).
- ``"float"``: NaN (or None) is stored as NULL and read back as ``float('nan')``;
  -0.0 is stored as 0.0 (SQLite keeps no sign of zero).

Every stored row also carries ``finished_utc``: when the row was committed, an
ISO-8601 timestamp with the explicit UTC offset ``+00:00``.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from datetime import UTC, datetime, timedelta
from numbers import Integral, Real
from types import MappingProxyType

__all__ = [
    "COLUMN_TYPES",
    "DOCKING_ERROR_COLUMNS",
    "FINISHED_COLUMN",
    "KEY_COLUMNS",
    "NULLABLE_INT_COLUMNS",
    "RESULT_COLUMNS",
    "SCHEMA_VERSION",
    "STATUSES",
    "ResultKey",
    "key_of",
    "normalize_row",
    "utc_now_iso",
]

#: Version of the stored layout; a store refuses a database written with another one.
SCHEMA_VERSION: int = 1

#: The docking error ξ's columns (mm, mm, deg), in results and in real-experiment tables.
DOCKING_ERROR_COLUMNS: tuple[str, str, str] = (
    "dock_err_x_mm",
    "dock_err_y_mm",
    "dock_err_theta_deg",
)

RESULT_COLUMNS: tuple[str, ...] = (
    "object_id", "face", "conveyor", "theta_deg", "run", "seed",
    *DOCKING_ERROR_COLUMNS,
    "y1", "y2", "success", "t_end_s", "status",
    "t_end_1_s", "t_end_2_s", "message", "state_pre", "state_end_1", "state_end_2",
)  # fmt: skip

_STR = frozenset({"object_id", "face", "conveyor", "status", "message"})
_INT = frozenset({"theta_deg", "run", "seed", "y1", "y2", "success"})


def _kind(name: str) -> str:
    if name in _STR or name.startswith("state_"):
        return "str"
    return "int" if name in _INT else "float"


#: Column name -> "str" | "int" | "float" (read-only mapping).
COLUMN_TYPES: Mapping[str, str] = MappingProxyType({name: _kind(name) for name in RESULT_COLUMNS})

KEY_COLUMNS: tuple[str, ...] = ("object_id", "face", "conveyor", "theta_deg", "run")
#: Integer columns that may be None (outcome not determined).
NULLABLE_INT_COLUMNS: frozenset[str] = frozenset({"y1", "y2", "success"})
STATUSES: tuple[str, ...] = ("ok", "invalid", "unstable", "error")
#: Added by the store to every row: commit time, ISO-8601 UTC.
FINISHED_COLUMN = "finished_utc"

#: (object_id, face, conveyor, theta_deg, run)
ResultKey = tuple[str, str, str, int, int]

_INT64 = (-(2**63), 2**63 - 1)
_REQUIRED_STR = frozenset({*KEY_COLUMNS, "status"}) - {"theta_deg", "run"}


def utc_now_iso() -> str:
    """The current time as ISO-8601 with offset ``+00:00`` (microseconds)."""
    return datetime.now(UTC).isoformat(timespec="microseconds")


def key_of(row: Mapping[str, object]) -> ResultKey:
    """The key (object_id, face, conveyor, theta_deg, run) of a normalised row."""
    return tuple(row[name] for name in KEY_COLUMNS)  # type: ignore[return-value]


def _to_str(name: str, value: object) -> str:
    if value is None and name not in _REQUIRED_STR:
        return ""
    if not isinstance(value, str):
        raise ValueError(f"column {name!r} must be a str, got {value!r}")
    if name in _REQUIRED_STR and not value:
        raise ValueError(f"column {name!r} must not be empty")
    if name == "status" and value not in STATUSES:
        raise ValueError(f"status must be one of {STATUSES}, got {value!r}")
    return str(value)


def _to_int(name: str, value: object) -> int | None:
    if value is None and name in NULLABLE_INT_COLUMNS:
        return None
    if not isinstance(value, Integral):
        raise ValueError(f"column {name!r} must be an int, got {value!r}")
    out = int(value)
    if not _INT64[0] <= out <= _INT64[1]:
        raise ValueError(f"column {name!r} does not fit a 64-bit integer: {out}")
    return out


def _to_float(name: str, value: object) -> float:
    if value is None:
        return math.nan
    if not isinstance(value, Real) or isinstance(value, bool):
        raise ValueError(f"column {name!r} must be a float, got {value!r}")
    return float(value) + 0.0  # -0.0 -> 0.0, as SQLite stores it


_CONVERT = {"str": _to_str, "int": _to_int, "float": _to_float}


def _finished(value: object, default: str) -> str:
    if value is None:
        return default
    when = value if isinstance(value, datetime) else None
    if isinstance(value, str):
        try:
            when = datetime.fromisoformat(value)
        except ValueError:
            when = None
    if when is None or when.utcoffset() != timedelta(0):
        raise ValueError(f"{FINISHED_COLUMN} must be a UTC ISO-8601 timestamp, got {value!r}")
    return when.astimezone(UTC).isoformat(timespec="microseconds")


def normalize_row(row: Mapping[str, object], finished_utc: str) -> dict[str, object]:
    """Check one result row and return it with plain Python values.

    Args:
        row: Exactly the `RESULT_COLUMNS`, optionally with `FINISHED_COLUMN` (kept when
            copying rows between stores). numpy scalars are accepted.
        finished_utc: Commit time to add when the row has none (ISO-8601 UTC).

    Returns:
        A new dict: `RESULT_COLUMNS` then `FINISHED_COLUMN`, values of the column types.

    Raises:
        ValueError: A missing or unknown column or a value of the wrong type: a
            programming error of the caller, not bad user input.
    """
    if not isinstance(row, Mapping):
        raise ValueError(f"a result row must be a mapping, got {type(row).__name__}")
    missing = [name for name in RESULT_COLUMNS if name not in row]
    if missing:
        raise ValueError(f"result row lacks column(s) {', '.join(missing)}")
    unknown = sorted(set(row) - set(RESULT_COLUMNS) - {FINISHED_COLUMN})
    if unknown:
        raise ValueError(f"result row has unknown column(s) {', '.join(map(str, unknown))}")
    out = {name: _CONVERT[COLUMN_TYPES[name]](name, row[name]) for name in RESULT_COLUMNS}
    out[FINISHED_COLUMN] = _finished(row.get(FINISHED_COLUMN), finished_utc)
    return out
