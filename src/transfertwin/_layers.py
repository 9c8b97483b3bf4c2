"""The package layers and the import graph read from the source (AST, no import).

`LAYERS` lists the packages bottom-up. A module may import its own package's private
modules, the public surface (`__init__`) of a package below its own, and the root's private
helpers (`transfertwin._errors`, `_atomic`, `_aio`, `_layers`, `_lazy`). Anything else
— a private module of another package, or a package at the same level or above — breaks the
layering. `tests/unit/test_layering.py` enforces it; `scripts/import_graph.py` draws it.

`import_cycles` finds the circles of the module graph: modules that import, directly or
through others, a module that imports them back (function-level imports included).
"""

from __future__ import annotations

import ast
from collections import defaultdict
from pathlib import Path

import networkx as nx

from transfertwin._lazy import type_checking_imports

__all__ = [
    "LAYERS",
    "ImportEdge",
    "import_cycles",
    "imports_of",
    "module_graph",
    "package_graph",
    "package_of",
    "violations",
]

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

_ROOT_HELPERS = ("_errors", "_atomic", "_aio", "_layers", "_lazy")

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


def _module_name(path: Path, src: Path) -> str:
    rel = path.relative_to(src.parent).with_suffix("")
    return ".".join(rel.parts[:-1] if rel.name == "__init__" else rel.parts)


#: The tests of `if TYPE_CHECKING:` blocks, whose imports never run.
_TYPE_CHECKING = ("TYPE_CHECKING", "typing.TYPE_CHECKING")


def _runtime_imports(tree: ast.AST) -> list[ast.Import | ast.ImportFrom]:
    """The import statements executed at run time: everywhere (functions included) except
    under `if TYPE_CHECKING:`, which type checkers read and the interpreter skips."""
    found: list[ast.Import | ast.ImportFrom] = []
    stack = [tree]
    while stack:
        node = stack.pop()
        if isinstance(node, ast.If) and ast.unparse(node.test) in _TYPE_CHECKING:
            stack += node.orelse
            continue
        if isinstance(node, ast.Import | ast.ImportFrom):
            found.append(node)
        stack += ast.iter_child_nodes(node)
    return found


class _Modules:
    """The modules under `src` (dotted names) and the lazy surfaces among them."""

    def __init__(self, src: Path) -> None:
        self.paths = {_module_name(p, src): p for p in sorted(src.rglob("*.py"))}
        self.lazy = {
            name: type_checking_imports(path)
            for name, path in self.paths.items()
            if path.name == "__init__.py" and "lazy_exports(" in path.read_text()
        }

    def target(self, module: str, name: str | None) -> str | None:
        """The module that `from module import name` (or `import module`) runs: a
        submodule `name`, else the module a lazy surface takes `name` from, else `module`."""
        if name is not None and f"{module}.{name}" in self.paths:
            return f"{module}.{name}"
        if name is not None and name in self.lazy.get(module, {}):
            return self.target(self.lazy[module][name], name)
        return module if module in self.paths else None


def module_graph(src: Path) -> dict[str, set[str]]:
    """Module → the modules it imports at run time (dotted names, `transfertwin.` prefix).

    `import transfertwin.a.b` points at `a.b` (not at the package `a` it passes through);
    `from transfertwin.a import x` at `a.x` if that is a module, else at the module a lazy
    surface (`transfertwin._lazy`) takes `x` from, else at `a`. Imports inside functions
    count (they run when called, and a circle that waits for a call is still a circle);
    imports under `if TYPE_CHECKING:` do not (they never run), except the re-exports of a
    lazy surface, which run on first access and so are followed through it.

    Args:
        src: The `transfertwin` package directory.
    """
    modules = _Modules(src)
    graph: dict[str, set[str]] = {m: set() for m in modules.paths}
    for module, path in modules.paths.items():
        for node in _runtime_imports(ast.parse(path.read_text(), str(path))):
            if isinstance(node, ast.Import):
                pairs = [(a.name, None) for a in node.names]
            elif node.module and node.level == 0:
                pairs = [(node.module, a.name) for a in node.names]
            else:
                continue
            for target in (modules.target(m, n) for m, n in pairs):
                if target is not None and target != module:
                    graph[module].add(target)
    return graph


def import_cycles(src: Path) -> list[list[str]]:
    """The circles of the module graph (`module_graph`): each a strongly connected component
    of more than one module, sorted; every module in it imports, directly or through others,
    every other. Empty when the imports form a DAG.

    Args:
        src: The `transfertwin` package directory.
    """
    digraph = nx.DiGraph([(a, b) for a, bs in module_graph(src).items() for b in bs])
    return sorted(sorted(c) for c in nx.strongly_connected_components(digraph) if len(c) > 1)
