"""Result rows for store tests and a NaN-aware, type-exact row comparison."""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence

#: The minimum result columns (docs/architecture.md, "Contracts"), written out independently.
DESIGN_COLUMNS = (
    "object_id", "face", "conveyor", "theta_deg", "run", "seed", "dock_err_x_mm",
    "dock_err_y_mm", "dock_err_theta_deg", "y1", "y2", "success", "t_end_s", "status",
)  # fmt: skip


def result_row(
    object_id: str = "o1",
    face: str = "front",
    conveyor: str = "left",
    theta_deg: int = 0,
    run: int = 0,
    **overrides: object,
) -> dict[str, object]:
    """A complete, valid result row; keyword arguments replace single cells."""
    row: dict[str, object] = {
        "object_id": object_id,
        "face": face,
        "conveyor": conveyor,
        "theta_deg": theta_deg,
        "run": run,
        "seed": 7,
        "dock_err_x_mm": 1.5,
        "dock_err_y_mm": -2.25,
        "dock_err_theta_deg": 0.5,
        "y1": 1,
        "y2": 1,
        "success": 1,
        "t_end_s": 3.0,
        "status": "ok",
        "t_end_1_s": 1.25,
        "t_end_2_s": 1.75,
        "message": "",
        "state_pre": "[-0.325, 0.0, 0.05]",
        "state_end_1": "",
        "state_end_2": "",
    }
    row.update(overrides)
    return row


def tricky_rows() -> list[dict[str, object]]:
    """Rows whose values break naive serialisation (NULLs, NaN, inf, quoting, big ints)."""
    return [
        result_row(theta_deg=-179, run=0, y1=None, y2=None, success=None, t_end_s=math.nan,
                   t_end_1_s=math.nan, t_end_2_s=math.nan, status="invalid",
                   message='settled, "not" pre-transfer\nsecond line'),
        result_row(theta_deg=180, run=2, y2=None, success=0, seed=2**63 - 1,
                   dock_err_x_mm=0.1 + 0.2, dock_err_y_mm=-1e-300, t_end_s=math.inf,
                   status="unstable", message="  padded, with ünïcödé ✓  "),
        result_row(object_id='o,"37"', face="back", conveyor="both", theta_deg=5, run=10,
                   seed=-(2**63), dock_err_theta_deg=1e-300, status="error", message="123",
                   state_pre="nan", state_end_1="[1e-05, 2.5]"),
        result_row(theta_deg=5, run=3),
    ]  # fmt: skip


def same_value(a: object, b: object) -> bool:
    """Equal values of the same type; NaN equals NaN; -0.0 differs from 0.0."""
    if type(a) is not type(b):
        return False
    if isinstance(a, float) and isinstance(b, float):
        if math.isnan(a) or math.isnan(b):
            return math.isnan(a) and math.isnan(b)
        return a == b and math.copysign(1.0, a) == math.copysign(1.0, b)
    return a == b


def assert_rows_equal(
    got: Sequence[Mapping[str, object]], expected: Sequence[Mapping[str, object]]
) -> None:
    """Rows equal cell by cell (same column order, `same_value`)."""
    assert len(got) == len(expected)
    for i, (g, e) in enumerate(zip(got, expected, strict=True)):
        assert list(g) == list(e), f"row {i}: columns differ"
        bad = {k: (g[k], e[k]) for k in e if not same_value(g[k], e[k])}
        assert not bad, f"row {i}: cells differ (got, expected): {bad}"


def sort_key(row: Mapping[str, object]) -> tuple[object, ...]:
    """The store key of a row, for ordering expected rows."""
    return tuple(row[name] for name in ("object_id", "face", "conveyor", "theta_deg", "run"))
