"""The study's symbols as math in the API reference (a griffe extension, mkdocs.yml).

Docstrings write the source's notation as plain text so that it reads in `help()` and an
editor: `E^V` (a virtual experiment), `E^P` (a physical one), `ȳ^MA` (the success share
smoothed over neighbouring angles), `TM^V`, `TU^V` (virtual transport module and transfer
unit), and units such as `kg/m^3`. On the site the same text would show a literal caret,
so while mkdocstrings loads the API this extension rewrites each such symbol outside code
into `$...$` math, which pymdownx.arithmatex and the vendored KaTeX typeset as on the
Background page (docs/background.md), and a unit's power into a superscript (kg/m³). Text
in backticks stays as it is: code is code.

`tests/unit/test_docs_math.py` loads the package through this extension and fails if a
docstring still shows a literal caret.
"""

from __future__ import annotations

import re
from typing import Any

import griffe

#: The source's symbols as written in plain text, and their TeX.
NOTATION = {
    "E^V": "E^V",
    "E^P": "E^P",
    "ȳ^MA": r"\overline{y}^{MA}",
    "TM^V": r"\mathrm{TM}^V",
    "TU^V": r"\mathrm{TU}^V",
}
#: One of the symbols as a word of its own (`E^P's` included; not inside `$...$`).
SYMBOL = re.compile(r"(?<![\$\w])(" + "|".join(re.escape(s) for s in NOTATION) + r")(?![\w\$^])")
#: A unit's power written with a caret (`kg/m^3`, `kg m^2`, `s^-1`), shown as superscript.
POWER = re.compile(r"(?<=[A-Za-z])\^(-?[0-9]+)\b")
SUPERSCRIPT = str.maketrans("-0123456789", "⁻⁰¹²³⁴⁵⁶⁷⁸⁹")
#: A caret between word characters: what a reader would see as a literal caret.
CARET = re.compile(r"\w\^\w")
#: Markdown code: a run of backticks, anything, the same run again.
CODE = re.compile(r"(`+)(?:.|\n)*?(?<!`)\1(?!`)")
#: Inline math already written as such.
MATH = re.compile(r"\$[^$\n]+\$")


def _spans(text: str, inside: re.Pattern[str]):
    """(is_inside, piece) for `text` cut at the matches of `inside`."""
    at = 0
    for m in inside.finditer(text):
        yield False, text[at : m.start()]
        yield True, m.group(0)
        at = m.end()
    yield False, text[at:]


def _prose_as_math(text: str) -> str:
    text = SYMBOL.sub(lambda m: f"${NOTATION[m.group(1)]}$", text)
    return POWER.sub(lambda m: m.group(1).translate(SUPERSCRIPT), text)


def as_math(text: str) -> str:
    """`text` with each of the study's symbols outside code written as `$...$` math and
    each unit's power as a superscript (`kg/m^3` → kg/m³)."""
    return "".join(piece if code else _prose_as_math(piece) for code, piece in _spans(text, CODE))


def literal_carets(text: str) -> list[str]:
    """The words of `text` that would show a literal caret: outside code and math."""
    found = []
    for code, piece in _spans(text, CODE):
        if not code:
            prose = MATH.sub(" ", piece)
            found += [prose[max(0, m.start() - 20) : m.end() + 20] for m in CARET.finditer(prose)]
    return found


class CaretsAsMath(griffe.Extension):
    """Rewrites every docstring that griffe loads with `as_math`."""

    def on_instance(self, *, obj: griffe.Object, **kwargs: Any) -> None:
        if obj.docstring is not None:
            obj.docstring.value = as_math(obj.docstring.value)
