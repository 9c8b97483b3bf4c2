"""The package layers and the import graph read from the source (AST, no import).

`LAYERS` lists the packages bottom-up. A module may import its own package's private
modules, the public surface (`__init__`) of a package below its own, and the root's private
helpers (`transfertwin._errors`, `_atomic`, `_layers`, `_lazy`). Anything else
— a private module of another package, or a package at the same level or above — breaks the
layering. `tests/unit/test_layering.py` enforces it; `scripts/import_graph.py` draws it.
"""

from __future__ import annotations

import ast
from collections import defaultdict
from pathlib import Path

__all__ = ["LAYERS", "ImportEdge", "imports_of", "package_graph", "package_of", "violations"]

#: Packages bottom-up; a package may import only packages listed before it (its ancestors'
#: public surfaces included: `study.calibration` may use `study.experiment`).
LAYERS: tuple[str, ...] = (
    "data",
    "ots",
    "store",
    "objects",
    "control",
    "sim",
    "perception",
    "study.docking",
    "navigation",
    "study.experiment",
    "study.fullstate",
    "study.adaptive",
    "study.calibration",
    "study.validation",
    "study",
    "plant",
    "rehearsal",
    "cps.aas",
    "cps.opcua",
    "cps.kg",
    "cps.apps",
    "cps.floor",
    "cps.hal",
    "cps.dispatch",
    "cps.node",
    "cps.roles",
    "cps",
    "report",
    "replay",
    "web",
    "cli",
)

_ROOT_HELPERS = ("_errors", "_atomic", "_layers", "_lazy")

ImportEdge = tuple[str, int, str]  # (importing module, line, imported module)


def imports_of(src: Path) -> list[ImportEdge]:
    """Every `transfertwin.*` import (module level or inside functions) under `src`.

    Args:
        src: The `transfertwin` package directory.
    """
    edges: list[ImportEdge] = []
    for path in sorted(src.rglob("*.py")):
        rel = path.relative_to(src.parent).with_suffix("")
        module = ".".join(rel.parts[:-1] if rel.name == "__init__" else rel.parts)
        for node in ast.walk(ast.parse(path.read_text(), str(path))):
            if isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
                names = [node.module]
                if node.module == "transfertwin":
                    names = [f"transfertwin.{a.name}" for a in node.names]
            elif isinstance(node, ast.Import):
                names = [a.name for a in node.names]
            else:
                continue
            edges += [(module, node.lineno, n) for n in names if n.startswith("transfertwin.")]
    return edges


def package_of(module: str) -> str | None:
    """The layer a dotted module belongs to (longest match), None for root helpers."""
    parts = module.split(".")[1:]
    for n in range(len(parts), 0, -1):
        name = ".".join(parts[:n])
        if name in LAYERS:
            return name
    return None


def _private_part(module: str, package: str) -> bool:
    rest = module.split(".")[1 + len(package.split(".")) :]
    return any(p.startswith("_") for p in rest)


def violations(src: Path) -> list[str]:
    """Imports that break the layering, as 'module:line imports target: why'."""
    out = []
    for module, line, target in imports_of(src):
        mine, theirs = package_of(module), package_of(target)
        if theirs is None:
            if target.split(".")[1] not in _ROOT_HELPERS:
                out.append(f"{module}:{line} imports {target}: not in any layer")
            continue
        if mine is None or mine == theirs or mine.startswith(theirs + "."):
            continue  # inside one package, or a sub-package using its parent's helpers
        if LAYERS.index(theirs) >= LAYERS.index(mine):
            out.append(f"{module}:{line} imports {target}: upward ({mine} -> {theirs})")
        elif _private_part(target, theirs):
            out.append(f"{module}:{line} imports {target}: private module of {theirs}")
    return out


def package_graph(src: Path) -> dict[str, set[str]]:
    """Layer → the layers it imports (its own excluded)."""
    graph: dict[str, set[str]] = defaultdict(set)
    for module, _, target in imports_of(src):
        mine, theirs = package_of(module), package_of(target)
        if mine and theirs and mine != theirs:
            graph[mine].add(theirs)
    return graph
