"""The docs' notation renders as math: the pages write the study's symbols as $E^V$ (typeset
by pymdownx.arithmatex and the KaTeX vendored under docs/javascripts/), never as a literal
caret in prose; the API reference's docstrings go through scripts/docs_notation.py, which
writes them as math there; the Background page names the source work and is linked from the
home page. (The built site's HTML is checked for literal carets by tests/unit/test_docs.py.)"""

from __future__ import annotations

import sys
from pathlib import Path

import pytest
import yaml

ROOT = Path(__file__).parents[2]
DOCS = ROOT / "docs"
#: Generated from the CLI's help text (plain text in code blocks, no math there).
GENERATED = {"reference/cli.md"}
sys.path.insert(0, str(ROOT / "scripts"))
from docs_notation import as_math, literal_carets  # noqa: E402


def _mkdocs() -> dict:
    return yaml.load((ROOT / "mkdocs.yml").read_text(encoding="utf-8"), Loader=yaml.BaseLoader)


def test_no_page_shows_a_literal_caret() -> None:
    bad = [
        f"{p.relative_to(ROOT)}: ...{words}..."
        for p in [ROOT / "README.md", *sorted(DOCS.rglob("*.md"))]
        if str(p.relative_to(DOCS) if p.is_relative_to(DOCS) else p) not in GENERATED
        for words in literal_carets(p.read_text(encoding="utf-8"))
    ]
    assert not bad, "write $E^V$, $E^P$, $\\overline{y}^{MA}$, 10<sup>9</sup>:\n" + "\n".join(bad)


@pytest.mark.parametrize(
    ("text", "math"),
    [
        ("one E^V, the E^P's rows", "one $E^V$, the $E^P$'s rows"),
        ("ȳ^MA of TM^V", r"$\overline{y}^{MA}$ of $\mathrm{TM}^V$"),
        ("density in kg/m^3, inertia kg m^2", "density in kg/m³, inertia kg m²"),
        ("as code: `E^V`, ``E^P``; as math: $E^V$", "as code: `E^V`, ``E^P``; as math: $E^V$"),
    ],
)
def test_docstring_notation_becomes_math_outside_code(text: str, math: str) -> None:
    assert as_math(text) == math
    assert not literal_carets(math)


def test_a_caret_outside_code_and_math_is_found() -> None:
    assert literal_carets("one E^V") and literal_carets("in kg/m^3") and literal_carets("10^9")
    assert not literal_carets("`E^V`, $E^V$, 10<sup>9</sup>")


def test_no_docstring_shows_a_literal_caret_in_the_api_reference() -> None:
    """The API pages load the package through the griffe extension that mkdocs.yml names;
    every docstring it loads (public or not) must then be free of literal carets."""
    import griffe

    (plugin,) = [p["mkdocstrings"] for p in _mkdocs()["plugins"] if "mkdocstrings" in p]
    options = plugin["handlers"]["python"]["options"]
    assert "scripts/docs_notation.py:CaretsAsMath" in options["extensions"]
    loader = griffe.GriffeLoader(
        extensions=griffe.load_extensions(str(ROOT / "scripts/docs_notation.py") + ":CaretsAsMath"),
        search_paths=[str(ROOT / "src")],
    )
    bad: list[str] = []
    todo = [loader.load("transfertwin")]
    while todo:
        obj = todo.pop()
        if obj.docstring is not None:
            bad += [f"{obj.path}: ...{w}..." for w in literal_carets(obj.docstring.value)]
        todo += [m for m in obj.members.values() if not m.is_alias]
    assert not bad, "\n".join(bad)


def test_math_is_typeset_by_the_vendored_katex() -> None:
    cfg = _mkdocs()
    exts = [e if isinstance(e, str) else next(iter(e)) for e in cfg["markdown_extensions"]]
    assert "pymdownx.arithmatex" in exts
    for asset in (*cfg["extra_javascript"], *cfg["extra_css"]):
        assert not asset.startswith(("http:", "https:", "//")), asset  # no CDN
        assert (DOCS / asset).is_file(), asset
    assert any((DOCS / "javascripts" / "katex" / "fonts").glob("KaTeX_Main-Regular.woff2"))


def test_the_background_page_names_the_source_and_is_linked_from_home() -> None:
    page = (DOCS / "background.md").read_text(encoding="utf-8")
    assert (
        "Predictive Object Transfer in Remanufacturing: A Cyber-Physical Approach Using "
        "Digital Twins" in page.replace("\n> ", " ").replace("*", "")
    )
    for symbol in ("$E^V$", "$E^P$", r"$\overline{y}^{MA}$", "Alg. 1 / Alg. 2", "Eq. 6.27"):
        assert symbol in page
    assert "(background.md)" in (DOCS / "index.md").read_text(encoding="utf-8")
