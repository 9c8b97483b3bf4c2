"""Lazy public surfaces for packages whose re-exports are heavy (PEP 562; stdlib only).

Such a package's ``__init__`` keeps its re-exports as imports under ``if TYPE_CHECKING:``
and its literal ``__all__``, and ends with ``__getattr__, __dir__ = lazy_exports(__name__,
__file__)``: a name is imported on first use, so ``from transfertwin.study import
run_study`` imports the runner and what it needs, not the calibration, statistics and
analysis modules beside it. A spawned study worker, which imports only the module of its
entry point, so starts in about half the time (docs/speed.md, "Worker start-up"). The imports
stay the one list of what comes from where: `lazy_exports` reads them from the source, type
checkers and the layering check (`transfertwin._layers`) see them as before, and
`tests/unit/test_lazy.py` checks that every name of ``__all__`` resolves.
"""

from __future__ import annotations

import ast
import importlib
import sys
from collections.abc import Callable
from pathlib import Path

__all__ = ["lazy_exports", "type_checking_imports"]


def type_checking_imports(init_file: str | Path) -> dict[str, str]:
    """Name → absolute module of the ``from M import a, b`` statements under the module's
    top-level ``if TYPE_CHECKING:`` blocks."""
    tree = ast.parse(Path(init_file).read_text(), str(init_file))
    where: dict[str, str] = {}
    for node in tree.body:
        if not (isinstance(node, ast.If) and ast.unparse(node.test) == "TYPE_CHECKING"):
            continue
        for stmt in node.body:
            if not (isinstance(stmt, ast.ImportFrom) and stmt.module and stmt.level == 0):
                raise ValueError(f"{init_file}:{stmt.lineno}: only absolute 'from' imports")
            for alias in stmt.names:
                name = alias.asname or alias.name
                if name in where:
                    raise ValueError(f"{init_file}:{stmt.lineno}: {name!r} imported twice")
                where[name] = stmt.module
    return where


def lazy_exports(
    package: str, init_file: str | Path
) -> tuple[Callable[[str], object], Callable[[], list[str]]]:
    """``__getattr__`` and ``__dir__`` for `package` (its ``__name__`` and ``__file__``).

    A name of the ``TYPE_CHECKING`` imports is imported from its module on first access
    and cached in the package (the next access is a plain lookup); so is a sub-package
    named as such an import's module (``transfertwin.study.calibration``). Anything else
    raises AttributeError.
    """
    where = type_checking_imports(init_file)
    prefix = package + "."
    tops = {m[len(prefix) :].split(".")[0] for m in where.values() if m.startswith(prefix)}
    subpackages = {m for m in tops if not m.startswith("_")}  # private modules stay hidden

    def __getattr__(name: str) -> object:  # noqa: N807 - PEP 562's name
        if name in where:
            value = getattr(importlib.import_module(where[name]), name)
        elif name in subpackages:
            value = importlib.import_module(prefix + name)
        else:
            raise AttributeError(f"module {package!r} has no attribute {name!r}")
        setattr(sys.modules[package], name, value)
        return value

    def __dir__() -> list[str]:  # noqa: N807 - PEP 562's name
        return sorted(set(vars(sys.modules[package])) | set(where) | subpackages)

    return __getattr__, __dir__
