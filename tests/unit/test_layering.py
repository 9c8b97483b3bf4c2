"""The layering of the package (docs/architecture.md): imports point down, only to public
surfaces, and the import graph in docs/architecture.md is the one the source has."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

from transfertwin._layers import LAYERS, import_cycles, imports_of, package_of, violations

ROOT = Path(__file__).resolve().parents[2]
SRC = ROOT / "src" / "transfertwin"


@pytest.fixture(scope="module")
def found() -> list[str]:
    return violations(SRC)


@pytest.mark.parametrize("package", LAYERS)
def test_package_imports_only_public_surfaces_below_it(package: str, found: list[str]) -> None:
    mine = [v for v in found if package_of(v.split(":")[0]) == package]
    assert mine == []


def test_every_module_belongs_to_a_layer() -> None:
    modules = {m for m, _, _ in imports_of(SRC)}
    stray = sorted(m for m in modules if package_of(m) is None and m.count(".") > 1)
    assert stray == []


def _tree(tmp_path: Path, files: dict[str, str]) -> Path:
    src = tmp_path / "transfertwin"
    for name, text in files.items():
        path = src / name
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(text)
    return src


def test_private_import_across_packages_is_reported(tmp_path: Path) -> None:
    src = _tree(tmp_path, {"report/_x.py": "from transfertwin.study.fullstate._states import a\n"})
    assert violations(src) == [
        "transfertwin.report._x:1 imports transfertwin.study.fullstate._states: "
        "private module of study.fullstate"
    ]


def test_upward_import_is_reported_even_inside_a_function(tmp_path: Path) -> None:
    src = _tree(tmp_path, {"sim/_x.py": "def f():\n    from transfertwin.study import run\n"})
    assert violations(src) == [
        "transfertwin.sim._x:2 imports transfertwin.study: upward (sim -> study)"
    ]


def test_sibling_sub_packages_follow_their_order(tmp_path: Path) -> None:
    src = _tree(tmp_path, {
        "study/docking/_x.py": "import transfertwin.study.experiment\n",
        "study/validation/_y.py": "from transfertwin.study.fullstate import clopper_pearson\n",
    })  # fmt: skip
    assert violations(src) == [
        "transfertwin.study.docking._x:1 imports transfertwin.study.experiment: "
        "upward (study.docking -> study.experiment)"
    ]


def test_architecture_import_graph_is_generated_from_the_source() -> None:
    check = subprocess.run(
        [sys.executable, str(ROOT / "scripts" / "import_graph.py"), "--check"], check=False
    )
    assert check.returncode == 0, "run: python scripts/import_graph.py --write"


# --- No circles: no module imports, directly or through others, a module
# that imports it back; imports inside functions count, `if TYPE_CHECKING:` ones do not.

def test_no_module_imports_itself_back() -> None:
    cycles = import_cycles(SRC)
    report = "\n".join(" -> ".join(c) for c in cycles)
    assert cycles == [], f"import circles:\n{report}"


def test_a_direct_circle_is_found(tmp_path: Path) -> None:
    src = _tree(tmp_path, {
        "a/__init__.py": "",
        "a/_x.py": "from transfertwin.a._y import f\n",
        "a/_y.py": "import transfertwin.a._x\n",
    })  # fmt: skip
    assert import_cycles(src) == [["transfertwin.a._x", "transfertwin.a._y"]]


def test_a_circle_through_a_third_module_is_found(tmp_path: Path) -> None:
    src = _tree(tmp_path, {
        "a/__init__.py": "from transfertwin.a._x import f\n",
        "a/_x.py": "from transfertwin.b import g\n",
        "b/__init__.py": "from transfertwin.b._z import g\n",
        "b/_z.py": "from transfertwin.a import _x\n",
        "c.py": "from transfertwin.a import f\n",  # imports the circle, is not in it
    })  # fmt: skip
    assert import_cycles(src) == [
        ["transfertwin.a._x", "transfertwin.b", "transfertwin.b._z"]
    ]


def test_a_circle_through_a_function_level_import_is_found(tmp_path: Path) -> None:
    src = _tree(tmp_path, {
        "a/__init__.py": "",
        "a/_x.py": "from transfertwin.a._y import f\n",
        "a/_y.py": "def f():\n    from transfertwin.a._x import g\n    return g\n",
    })  # fmt: skip
    assert import_cycles(src) == [["transfertwin.a._x", "transfertwin.a._y"]]


def test_a_type_checking_import_back_is_no_circle(tmp_path: Path) -> None:
    src = _tree(tmp_path, {
        "a/__init__.py": "",
        "a/_x.py": "from transfertwin.a._y import f\n",
        "a/_y.py": "from typing import TYPE_CHECKING\n"
                   "if TYPE_CHECKING:\n    from transfertwin.a._x import Thing\n",
    })  # fmt: skip
    assert import_cycles(src) == []


def test_a_lazy_surface_is_followed_to_the_module_it_takes_a_name_from(tmp_path: Path) -> None:
    lazy = ("from typing import TYPE_CHECKING\n"
            "from transfertwin._lazy import lazy_exports\n"
            "if TYPE_CHECKING:\n    from transfertwin.b._z import g\n"
            "__getattr__, __dir__ = lazy_exports(__name__, __file__)\n")  # fmt: skip
    src = _tree(tmp_path, {
        "a/__init__.py": "",
        "a/_x.py": "from transfertwin.b import g\n",  # runs b._z on first access
        "b/__init__.py": lazy,
        "b/_z.py": "from transfertwin.a._x import f\n",
    })  # fmt: skip
    assert import_cycles(src) == [["transfertwin.a._x", "transfertwin.b._z"]]
