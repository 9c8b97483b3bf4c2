"""What the floor's TOML files share: reading one with one clear error line (`read_toml`),
checking its tables and values (`table`, `finite`, `nonempty`), and writing a value back
(`toml_value`)."""

from __future__ import annotations

import json
import math
import tomllib
from pathlib import Path

from transfertwin._errors import InputError

__all__ = ["finite", "nonempty", "read_toml", "table", "toml_value"]


def read_toml(path: Path, *, missing: str, unreadable: str) -> dict:
    """The parsed document at `path`; InputError ``PATH: MISSING`` when there is no such file,
    ``PATH: UNREADABLE (why)`` when it cannot be read or is not TOML."""
    try:
        return tomllib.loads(path.read_text())
    except FileNotFoundError:
        raise InputError(f"{path}: {missing}") from None
    except (OSError, UnicodeDecodeError, tomllib.TOMLDecodeError) as exc:
        raise InputError(f"{path}: {unreadable} ({exc})") from None


def table(doc: dict, key: str) -> dict:
    """The table `key` of `doc` (empty when absent; InputError when it is no table)."""
    value = doc.get(key, {})
    if not isinstance(value, dict):
        raise InputError(f"[{key}] must be a table")
    return value


def finite(doc: dict, key: str, where: str) -> float:
    """`doc[key]` as a finite number (InputError naming `where` otherwise)."""
    value = doc.get(key)
    if isinstance(value, bool) or not isinstance(value, int | float) or not math.isfinite(value):
        raise InputError(f"{where}: {key} must be a finite number, got {value!r}")
    return float(value)


def nonempty(doc: dict, key: str, where: str) -> str:
    """`doc[key]` as a non-empty string (InputError naming `where` otherwise)."""
    value = doc.get(key)
    if not isinstance(value, str) or not value:
        raise InputError(f"{where}: {key} must be a non-empty string, got {value!r}")
    return value


def toml_value(value: object) -> str:
    """`value` as TOML: a boolean, number, list or (JSON-escaped) basic string."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, int | float):
        return repr(value)
    if isinstance(value, list | tuple):
        return "[" + ", ".join(toml_value(v) for v in value) + "]"
    return json.dumps(str(value))  # a TOML basic string is a JSON string
