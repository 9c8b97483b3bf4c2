"""The ots layer imports only numpy, the standard library and transfertwin._errors."""

from __future__ import annotations

import ast
import sys
from pathlib import Path

import transfertwin.ots

ALLOWED_PREFIXES = ("numpy", "transfertwin._errors", "transfertwin.ots")


def _imports(path: Path) -> list[str]:
    names = []
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.Import):
            names += [alias.name for alias in node.names]
        elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
            names.append(node.module)
    return names


def test_ots_imports_only_numpy_stdlib_and_errors() -> None:
    package_dir = Path(transfertwin.ots.__file__).parent
    files = sorted(package_dir.glob("*.py"))
    assert files
    for path in files:
        for name in _imports(path):
            top = name.split(".")[0]
            allowed = top in sys.stdlib_module_names or name.startswith(ALLOWED_PREFIXES)
            assert allowed, f"{path.name} imports {name}"


def test_public_names_are_exported() -> None:
    for name in transfertwin.ots.__all__:
        assert hasattr(transfertwin.ots, name), name
    assert len(set(transfertwin.ots.__all__)) == len(transfertwin.ots.__all__)
