"""The documentation site: paths into docs/ that the README and the code name exist, every
page is in mkdocs.yml's nav, and (slow) `mkdocs build --strict` passes and no built page shows
a literal caret in its prose (`E^V`, `kg/m^3`: the notation renders as math).

The site is built by `.ci/run` too; the fast checks here catch a moved page without mkdocs.
"""

from __future__ import annotations

import html
import re
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).parents[2]
DOC_PATH = re.compile(r"docs/[\w./-]+\.(?:md|png)")
SCANNED = ("README.md", "src", "tests", "benchmarks", "scripts", "pyproject.toml", "mkdocs.yml")


def mentioned_doc_paths() -> dict[str, set[str]]:
    """Every path into docs/ (a page or an image) that the README, code or scripts name."""
    found: dict[str, set[str]] = {}
    for top in SCANNED:
        base = ROOT / top
        files = [base] if base.is_file() else sorted(base.rglob("*"))
        for path in files:
            if path.suffix not in (".py", ".md", ".toml", ".yml") or "egg-info" in str(path):
                continue
            for match in DOC_PATH.findall(path.read_text(encoding="utf-8", errors="replace")):
                found.setdefault(match, set()).add(str(path.relative_to(ROOT)))
    return found


def test_every_mentioned_docs_path_exists() -> None:
    missing = {p: sorted(w) for p, w in mentioned_doc_paths().items() if not (ROOT / p).exists()}
    assert not missing, f"paths into docs/ that do not exist (mentioned by): {missing}"


def test_every_page_is_in_the_nav() -> None:
    nav = (ROOT / "mkdocs.yml").read_text(encoding="utf-8").split("\nnav:", 1)[1]
    listed = set(re.findall(r"([\w./-]+\.md)\s*$", nav, flags=re.M))
    pages = {str(p.relative_to(ROOT / "docs")) for p in (ROOT / "docs").rglob("*.md")}
    assert pages - listed == set(), f"pages missing from mkdocs.yml's nav: {pages - listed}"
    assert listed - pages == set(), f"nav entries without a page: {listed - pages}"


@pytest.mark.slow
def test_the_site_builds_strictly(tmp_path: Path) -> None:
    mkdocs = Path(sys.executable).with_name("mkdocs")
    if not mkdocs.exists() and shutil.which("mkdocs") is None:
        pytest.skip("mkdocs is not installed (pip install -e '.[docs]')")
    cmd = [str(mkdocs) if mkdocs.exists() else "mkdocs", "build", "--strict", "-d", str(tmp_path)]
    done = subprocess.run(cmd, cwd=ROOT, capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stderr[-4000:]
    assert (tmp_path / "reference/cli/index.html").is_file()
    carets = [f"{page.relative_to(tmp_path)}: ...{words}..." for page in
              sorted(tmp_path.rglob("*.html")) for words in shown_carets(page)]  # fmt: skip
    shown = "a page shows a literal caret (scripts/docs_notation.py):\n"
    assert not carets, shown + "\n".join(carets)


#: What a reader does not see as prose: code, scripts, and the math KaTeX typesets.
HIDDEN = re.compile(
    r"<(script|style|pre|code)\b.*?</\1>|<(span|div) class=\"arithmatex\">.*?</\2>", re.S
)


def shown_carets(page: Path) -> list[str]:
    """The words around each literal caret in the prose of a built page (`E^V`, `m^3`)."""
    text = html.unescape(re.sub(r"<[^>]+>", " ", HIDDEN.sub(" ", page.read_text("utf-8"))))
    return [text[max(0, m.start() - 30) : m.end() + 30] for m in re.finditer(r"\w\^\w", text)]
