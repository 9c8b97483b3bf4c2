"""The docs' notation renders as math: the pages write the study's symbols as $E^V$ (typeset
by pymdownx.arithmatex and the KaTeX vendored under docs/javascripts/), never as a literal
caret in prose; the Background page names the source work and is linked from the home page."""

from __future__ import annotations

import re
from pathlib import Path

import yaml

ROOT = Path(__file__).parents[2]
DOCS = ROOT / "docs"
#: The study's symbols as carets; outside code they must be written as math.
CARETS = re.compile(r"(?<![\$\w])(?:E\^[VP]|ȳ\^MA)(?![\w\$])")
#: Generated from the CLI's help text (plain text, no math there).
GENERATED = {"reference/cli.md"}


def _prose(text: str) -> list[str]:
    """The page's lines outside fenced code, with inline code spans cut out."""
    out, fence = [], None
    for line in text.split("\n"):
        m = re.match(r"\s*(```|~~~)", line)
        if m:
            fence = (
                m.group(1) if fence is None else (None if line.strip().startswith(fence) else fence)
            )
            continue
        if fence is None:
            out.append("".join(line.split("`")[0::2]))
    return out


def test_no_page_writes_the_study_symbols_with_a_literal_caret() -> None:
    bad = [
        f"{p.relative_to(DOCS)}: {line.strip()}"
        for p in sorted(DOCS.rglob("*.md"))
        if str(p.relative_to(DOCS)) not in GENERATED
        for line in _prose(p.read_text(encoding="utf-8"))
        if CARETS.search(line)
    ]
    assert not bad, "write $E^V$, $E^P$, $\\overline{y}^{MA}$:\n" + "\n".join(bad)


def test_math_is_typeset_by_the_vendored_katex() -> None:
    cfg = yaml.load((ROOT / "mkdocs.yml").read_text(encoding="utf-8"), Loader=yaml.BaseLoader)
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
