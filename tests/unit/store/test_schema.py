"""Result-table constants and the store layer's import boundary."""

from __future__ import annotations

import ast
import sys
from pathlib import Path

import pytest

import transfertwin.store as store_pkg
from tests.unit.store.rows import DESIGN_COLUMNS
from transfertwin.store import (
    COLUMN_TYPES,
    KEY_COLUMNS,
    NULLABLE_INT_COLUMNS,
    RESULT_COLUMNS,
    SCHEMA_VERSION,
    STATUSES,
)

ALLOWED_IMPORTS = {"numpy", "pyarrow", "transfertwin._errors", "transfertwin.store"}


def test_result_columns_start_with_the_design_contract() -> None:
    assert RESULT_COLUMNS[: len(DESIGN_COLUMNS)] == DESIGN_COLUMNS
    assert len(set(RESULT_COLUMNS)) == len(RESULT_COLUMNS)


def test_every_column_has_a_type() -> None:
    assert list(COLUMN_TYPES) == list(RESULT_COLUMNS)
    assert set(COLUMN_TYPES.values()) == {"str", "int", "float"}
    ints = {name for name, kind in COLUMN_TYPES.items() if kind == "int"}
    assert ints == {"theta_deg", "run", "seed", "y1", "y2", "success"}
    assert {"y1", "y2", "success"} == NULLABLE_INT_COLUMNS
    with pytest.raises(TypeError):
        COLUMN_TYPES["run"] = "str"  # type: ignore[index]


def test_key_statuses_and_version() -> None:
    assert KEY_COLUMNS == ("object_id", "face", "conveyor", "theta_deg", "run")
    assert STATUSES == ("ok", "invalid", "unstable", "error")
    assert SCHEMA_VERSION == 1


def test_public_surface_is_exported() -> None:
    for name in store_pkg.__all__:
        assert hasattr(store_pkg, name), name


def _imports(path: Path) -> set[str]:
    names: set[str] = set()
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.Import):
            names.update(alias.name for alias in node.names)
        elif isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            names.add(node.module)
    return names


def test_store_imports_only_stdlib_numpy_pyarrow_and_errors() -> None:
    folder = Path(store_pkg.__file__).parent
    for path in sorted(folder.glob("*.py")):
        for name in _imports(path):
            top = name.split(".")[0]
            allowed = top in sys.stdlib_module_names or any(
                name == ok or name.startswith(ok + ".") for ok in ALLOWED_IMPORTS
            )
            assert allowed, f"{path.name} imports {name}"
