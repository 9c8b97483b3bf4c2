"""The `--write` / `--check` command line the generator scripts share.

A generated page section sits between a BEGIN and an END marker line; a script renders it
from the code and `generated_section_main` prints it, writes it into the page (`--write`)
or exits 1 when the page's section differs (`--check`, what the tests run). Used by
cli_reference.py, import_graph.py and information_model.py, run as scripts
(`python scripts/NAME.py`), so this module is found beside them.
"""

from __future__ import annotations

import argparse
from collections.abc import Callable
from pathlib import Path


def generated_section_main(
    script: str, doc: str, page: Path, begin: str, end: str, render: Callable[[], str]
) -> int:
    """Print, write (`--write`) or check (`--check`) the section `render()` makes of `page`.

    Args:
        script: The calling script's path (its `__file__`), named in the hint a stale
            check prints.
        doc: The script's docstring: its first line describes the command.
        page: The page that holds the section between the `begin` and `end` lines.
        begin, end: The marker lines; `render()` returns them with the section.
        render: Makes the section from the code.

    Returns:
        The exit status: 0, or 1 when `--check` finds the page stale.
    """
    parser = argparse.ArgumentParser(description=doc.splitlines()[0])
    parser.add_argument("--write", action="store_true", help="replace the page's section")
    parser.add_argument("--check", action="store_true", help="exit 1 if the section is stale")
    args = parser.parse_args()
    section = render()
    if not (args.write or args.check):
        print(section)
        return 0
    text = page.read_text(encoding="utf-8")
    start, stop = text.index(begin), text.index(end) + len(end)
    if args.check:
        if text[start:stop] == section:
            return 0
        script_path = Path(script).resolve()
        shown = page.relative_to(script_path.parents[1])
        print(f"{shown} is stale: run python scripts/{script_path.name} --write")
        return 1
    page.write_text(text[:start] + section + text[stop:], encoding="utf-8")
    return 0
