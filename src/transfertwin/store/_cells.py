"""Lenient cell parsers for reading result tables (CSV text or Parquet values).

Each parser takes a CSV string or a Python value and returns the column type of
`COLUMN_TYPES`; it raises ValueError with a short reason otherwise.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from numbers import Integral, Real

__all__ = ["PARSERS", "infer_column", "parse_float", "parse_int", "parse_str"]


def parse_str(value: object) -> str:
    """Text; None becomes ``""``; numbers become their decimal text."""
    if value is None:
        return ""
    if isinstance(value, str):
        return value
    if isinstance(value, Integral):
        return str(int(value))
    if isinstance(value, Real):
        return repr(float(value))
    raise ValueError(f"{value!r} is not text")


def parse_int(value: object) -> int | None:
    """A whole number; None, ``""`` and NaN become None; ``"3.0"`` becomes 3."""
    if value is None:
        return None
    if isinstance(value, Integral):
        return int(value)
    number = value
    if isinstance(value, str):
        text = value.strip()
        if not text:
            return None
        try:
            return int(text)
        except ValueError:
            number = _float_or_none(text)
    if isinstance(number, Real):
        number = float(number)
        if math.isnan(number):
            return None
        if number.is_integer():
            return int(number)
    raise ValueError(f"{value!r} is not an integer")


def _float_or_none(text: str) -> float | None:
    try:
        return float(text)
    except ValueError:
        return None


def parse_float(value: object) -> float:
    """A float; None and ``""`` become NaN."""
    if value is None:
        return math.nan
    if isinstance(value, Real) and not isinstance(value, bool):
        return float(value)
    if isinstance(value, str):
        text = value.strip()
        if not text:
            return math.nan
        try:
            return float(text)
        except ValueError:
            pass
    raise ValueError(f"{value!r} is not a number")


PARSERS: dict[str, Callable[[object], object]] = {
    "str": parse_str,
    "int": parse_int,
    "float": parse_float,
}


def _strict_int(text: str) -> int | None:
    return int(text) if text.strip() else None


def infer_column(values: list[object]) -> list[object]:
    """Type an extra CSV column: int if every filled cell is an integer, else float if
    every filled cell is a number, else text. Values that are not all text (Parquet)
    are returned unchanged.
    """
    if not values or not all(isinstance(v, str) for v in values):
        return values
    if not any(v.strip() for v in values):  # type: ignore[union-attr]
        return values
    for parse in (_strict_int, parse_float):
        try:
            return [parse(v) for v in values]
        except ValueError:
            continue
    return values
