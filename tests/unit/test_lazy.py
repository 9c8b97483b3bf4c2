"""Lazy package surfaces (`transfertwin._lazy`): the same names as before, resolved on first
use, and a study worker that starts without the statistics and calibration modules."""

from __future__ import annotations

import importlib
import subprocess
import sys
from pathlib import Path

import pytest

from transfertwin._lazy import lazy_exports, type_checking_imports

SRC = Path(__file__).resolve().parents[2] / "src"
LAZY = sorted(
    ".".join(p.parent.relative_to(SRC).parts)
    for p in (SRC / "transfertwin").rglob("__init__.py")
    if "lazy_exports(__name__, __file__)" in p.read_text()
)


def test_the_study_packages_are_lazy() -> None:
    assert {"transfertwin.study", "transfertwin.study.experiment"} <= set(LAZY)


@pytest.mark.parametrize("package", LAZY)
def test_all_lists_exactly_the_type_checking_imports(package: str) -> None:
    module = importlib.import_module(package)
    assert sorted(module.__all__) == sorted(type_checking_imports(module.__file__))


@pytest.mark.parametrize("package", LAZY)
def test_every_exported_name_resolves_to_its_modules_object(package: str) -> None:
    module = importlib.import_module(package)
    where = type_checking_imports(module.__file__)
    for name in module.__all__:
        assert getattr(module, name) is getattr(importlib.import_module(where[name]), name)
    assert set(module.__all__) <= set(dir(module))


def test_unknown_names_raise_attribute_error_and_subpackages_resolve() -> None:
    study = importlib.import_module("transfertwin.study")
    with pytest.raises(AttributeError, match="has no attribute 'no_such_name'"):
        study.no_such_name  # noqa: B018
    assert study.calibration is importlib.import_module("transfertwin.study.calibration")


def test_a_study_worker_imports_no_statistics_or_calibration_modules() -> None:
    heavy = ("scipy.stats", "statsmodels", "pandas", "optuna", "transfertwin.study.calibration")
    code = (
        "import sys, transfertwin.study.experiment._worker as w\n"
        "assert callable(w.run_row) and callable(w.exit_with_parent)\n"
        f"print(','.join(m for m in {heavy!r} if m in sys.modules))\n"
    )
    out = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, check=True,
        env={"PYTHONPATH": str(SRC), "PATH": "/usr/bin:/bin"},
    )  # fmt: skip
    assert out.stdout.strip() == ""


def test_type_checking_imports_reads_only_the_guarded_block(tmp_path: Path) -> None:
    init = tmp_path / "__init__.py"
    init.write_text(
        "from typing import TYPE_CHECKING\nimport os\n"
        "if TYPE_CHECKING:\n    from pkg.a import x, y as z\n    from pkg.b import w\n"
    )
    assert type_checking_imports(init) == {"x": "pkg.a", "z": "pkg.a", "w": "pkg.b"}


@pytest.mark.parametrize(
    ("block", "message"),
    [
        ("    from .a import x\n", "only absolute 'from' imports"),
        ("    import pkg.a\n", "only absolute 'from' imports"),
        ("    from pkg.a import x\n    from pkg.b import x\n", "'x' imported twice"),
    ],
)
def test_type_checking_imports_rejects_what_it_cannot_resolve(
    tmp_path: Path, block: str, message: str
) -> None:
    init = tmp_path / "__init__.py"
    init.write_text("from typing import TYPE_CHECKING\nif TYPE_CHECKING:\n" + block)
    with pytest.raises(ValueError, match=message):
        lazy_exports("pkg", init)
