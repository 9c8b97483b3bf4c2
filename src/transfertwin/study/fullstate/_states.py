"""Result rows to per-state statistics (Eq. 6.26 and Clopper–Pearson, Sec. 6.7).

Input is a results table as an iterable of mappings (one experiment each) with
at least ``object_id, face, conveyor, theta_deg, success`` and optionally
``status``. A missing or empty status counts as ``'ok'`` (real-experiment CSVs
have none). Only ``'ok'`` rows enter n and k; ``'invalid'``, ``'unstable'`` and
``'error'`` rows are counted per state but never as success or failure.
"""

from __future__ import annotations

import re
from collections.abc import Iterable, Iterator, Mapping
from dataclasses import dataclass

import numpy as np

from transfertwin._errors import InputError
from transfertwin.ots import (
    CONVEYORS,
    FACES,
    check_theta_deg,
    parse_conveyor,
    parse_face,
    state_index,
)
from transfertwin.study.fullstate._intervals import clopper_pearson_array

__all__ = [
    "STATES_COLUMNS",
    "STATUSES",
    "ResultRecord",
    "StateStat",
    "iter_records",
    "object_sort_key",
    "parse_row",
    "state_order",
    "state_table",
]

STATUSES = ("ok", "invalid", "unstable", "error")
#: Header of ``states.csv`` written by `analyze`: one row per state. A state belongs to
#: the left series (conveyor left or both), the right series (right or both) or both;
#: ``y_ma_left``/``y_ma_right`` hold its smoothed value ȳ^MA (Eq. 6.27) in each.
STATES_COLUMNS = (
    "object_id", "face", "conveyor", "theta_deg",
    "n", "k", "y_mean", "y_ma_left", "y_ma_right", "ci_low", "ci_high",
)  # fmt: skip


def object_sort_key(object_id: str) -> tuple:
    """Natural order of object ids: ``o2`` before ``o10``."""
    return tuple((0, int(p)) if p.isdigit() else (1, p) for p in re.split(r"(\d+)", object_id))


@dataclass(frozen=True, slots=True)
class ResultRecord:
    """One experiment row, validated (labels per Eq. 5.5, 5.6, 6.4).

    Attributes:
        object_id: Object label.
        face: ``'front'`` or ``'back'``.
        conveyor: ``'left'``, ``'both'`` or ``'right'``.
        theta_deg: Yaw, integer degrees in -179..180.
        success: 1 or 0 for ``'ok'`` rows, ``None`` otherwise.
        status: One of `STATUSES`.
    """

    object_id: str
    face: str
    conveyor: str
    theta_deg: int
    success: int | None
    status: str


_STATE_CACHE: dict[tuple, tuple[str, str, int]] = {}


def _state_labels(face: object, conveyor: object, theta: object) -> tuple[str, str, int]:
    raw = (face, conveyor, theta)
    try:
        return _STATE_CACHE[raw]
    except (KeyError, TypeError):  # not seen yet, or unhashable (then rejected below)
        pass
    key = (parse_face(face), parse_conveyor(conveyor), check_theta_deg(theta))
    state_index(*key)  # Eq. 6.7 membership, raises InputError
    _STATE_CACHE[raw] = key
    return key


_NUMBER_TYPES = (bool, int, float, np.bool_, np.integer, np.floating)


def _parse_success(value: object) -> int:
    if isinstance(value, str):
        value = value.strip()
        if value in ("0", "1"):
            return int(value)
    elif isinstance(value, (bool, int, float, np.bool_, np.integer, np.floating)) and value in (
        0,
        1,
    ):
        return int(value)
    raise InputError(f"success must be 0 or 1 for an 'ok' row, got {value!r}")


def parse_row(row: Mapping[str, object] | ResultRecord) -> ResultRecord:
    """Validate one results-table row.

    Raises:
        InputError: On a missing column, unknown status, bad label or success value.
    """
    if isinstance(row, ResultRecord):
        return row
    try:
        raw_id, face, conveyor, theta = (
            row["object_id"], row["face"], row["conveyor"], row["theta_deg"]
        )  # fmt: skip
    except KeyError as exc:
        raise InputError(f"results row lacks column {exc.args[0]!r}") from None
    object_id = str(raw_id).strip() if raw_id is not None else ""
    if not object_id:
        raise InputError("results row has an empty object_id")
    status = row.get("status")
    status = "ok" if status is None or status == "" else str(status).strip().lower()
    if status not in STATUSES:
        raise InputError(f"status must be one of {', '.join(STATUSES)}, got {row.get('status')!r}")
    face, conveyor, theta = _state_labels(face, conveyor, theta)
    success = _parse_success(row.get("success")) if status == "ok" else None
    return ResultRecord(object_id, face, conveyor, theta, success, status)


def iter_records(rows: Iterable[Mapping[str, object] | ResultRecord]) -> Iterator[ResultRecord]:
    """`parse_row` over rows; errors name the 1-based row number."""
    for i, row in enumerate(rows, start=1):
        try:
            yield parse_row(row)
        except InputError as exc:
            raise InputError(f"results row {i}: {exc}") from None


@dataclass(frozen=True)
class StateStat:
    """Statistics of one pre-transfer state of one object (Eq. 6.26, Sec. 6.7).

    Attributes:
        object_id, face, conveyor, theta_deg: The state.
        n: ``'ok'`` experiments; k: successes among them.
        y_mean: k/n (Eq. 6.26), NaN when n = 0.
        ci_low, ci_high: Clopper–Pearson 95 % bounds, NaN when n = 0.
        n_invalid, n_unstable, n_error: Excluded rows by status.
    """

    object_id: str
    face: str
    conveyor: str
    theta_deg: int
    n: int
    k: int
    y_mean: float
    ci_low: float
    ci_high: float
    n_invalid: int = 0
    n_unstable: int = 0
    n_error: int = 0

    @property
    def key(self) -> tuple[str, str, str, int]:
        """``(object_id, face, conveyor, theta_deg)``."""
        return (self.object_id, self.face, self.conveyor, self.theta_deg)


def state_order(key: tuple[str, str, str, int]) -> tuple:
    return (object_sort_key(key[0]), FACES.index(key[1]), CONVEYORS.index(key[2]), key[3])


def state_table(rows: Iterable[Mapping[str, object] | ResultRecord]) -> list[StateStat]:
    """Aggregate results per (object_id, face, conveyor, theta_deg) (Eq. 6.26).

    Returns:
        One `StateStat` per state seen, ordered by object (natural), face,
        conveyor (left, both, right) and θ.
    """
    counts: dict[tuple[str, str, str, int], list[int]] = {}
    slot = {"ok": 0, "invalid": 2, "unstable": 3, "error": 4}
    for rec in iter_records(rows):
        c = counts.setdefault((rec.object_id, rec.face, rec.conveyor, rec.theta_deg), [0] * 5)
        c[slot[rec.status]] += 1
        if rec.success:
            c[1] += 1
    keys = sorted(counts, key=state_order)
    n = np.array([counts[key][0] for key in keys], dtype=np.int64)
    k = np.array([counts[key][1] for key in keys], dtype=np.int64)
    low, high = clopper_pearson_array(k, n)
    out = []
    for i, key in enumerate(keys):
        c = counts[key]
        y = c[1] / c[0] if c[0] else float("nan")
        out.append(StateStat(*key, c[0], c[1], y, float(low[i]), float(high[i]), *c[2:]))
    return out
