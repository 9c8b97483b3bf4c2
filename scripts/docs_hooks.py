"""MkDocs hook: reference pages generated from the code at build time (mkdocs.yml `hooks`).

A page asks for a generated block with a marker comment on a line of its own:

- `<!-- generated:result-columns -->`: the result table's columns and types
  (`transfertwin.store.RESULT_COLUMNS`, `COLUMN_TYPES`, `KEY_COLUMNS`, `STATUSES`);
- `<!-- generated:profile-settings -->`: every setting of a physics profile by the dotted
  name a profile TOML or `--set` uses, with its type and default (`SceneConfig`);
- `<!-- generated:information-model -->`: per asset class the OperationalData properties and
  the ControlInterface operations (`transfertwin.cps.aas.OPERATIONAL_DATA`,
  `CONTROL_INTERFACE`).

So the reference cannot drift from the code: a renamed setting changes the page on the next
build, and `mkdocs build --strict` fails if a marker's generator raises. The command reference
is written into its page by `scripts/cli_reference.py` and checked by a unit test instead, so
that it reads the same on GitHub as on the site.
"""

from __future__ import annotations

import dataclasses
import sys
import typing
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
if str(ROOT / "src") not in sys.path:
    sys.path.insert(0, str(ROOT / "src"))


def result_columns_markdown() -> str:
    """The result table's columns in stored order, with type, key and nullability."""
    from transfertwin.store import (
        COLUMN_TYPES,
        FINISHED_COLUMN,
        KEY_COLUMNS,
        NULLABLE_INT_COLUMNS,
        RESULT_COLUMNS,
        STATUSES,
    )

    rows = ["| column | type | key | may be empty |", "|---|---|---|---|"]
    for name in (*RESULT_COLUMNS, FINISHED_COLUMN):
        kind = COLUMN_TYPES.get(name, "str")
        empty = {"float": "NULL → NaN", "int": "NULL" if name in NULLABLE_INT_COLUMNS else ""}
        required = name in KEY_COLUMNS or name in ("status", FINISHED_COLUMN)
        note = empty.get(kind, "" if required else '""')
        rows.append(f"| `{name}` | {kind} | {'yes' if name in KEY_COLUMNS else ''} | {note} |")
    statuses = ", ".join(f"`{s}`" for s in STATUSES)
    return "\n".join([*rows, "", f"Statuses: {statuses}."])


def _settings(cls: type, prefix: str, default: object):
    """(dotted name, type text, default) for every leaf field of a config dataclass."""
    hints = typing.get_type_hints(cls)
    for field in dataclasses.fields(cls):
        value = getattr(default, field.name)
        name = f"{prefix}{field.name}"
        if dataclasses.is_dataclass(value) and not isinstance(value, type):
            yield from _settings(type(value), f"{name}.", value)
        else:
            kind = getattr(hints[field.name], "__name__", None) or str(hints[field.name])
            yield name, str(kind).replace("typing.", ""), value


def profile_settings_markdown() -> str:
    """Every profile setting with its type, its default (`SceneConfig()`, the 'fast'
    profile) and the value of each other built-in profile where it differs."""
    from transfertwin.sim import PROFILES, SceneConfig, scene_profile

    others = [name for name in PROFILES if name != "fast"]
    values = {name: dict((n, v) for n, _, v in _settings(SceneConfig, "", scene_profile(name)))
              for name in others}  # fmt: skip
    head = "| setting | type | default | " + " | ".join(f"`{n}`" for n in others) + " |"
    rows = [head, "|---|---|---|" + "---|" * len(others)]
    for name, kind, value in _settings(SceneConfig, "", SceneConfig()):
        cells = [_cell(kind), _cell(repr(value))]
        cells += [_cell(repr(values[o][name])) if values[o][name] != value else ""
                  for o in others]  # fmt: skip
        rows.append(f"| `{name}` | " + " | ".join(cells) + " |")
    return "\n".join(rows)


def _cell(text: str) -> str:
    """`text` as inline code in a table cell (pipes escaped)."""
    return "`" + text.replace("|", "\\|") + "`"


def _args(args) -> str:
    return ", ".join(f"{a.id_short}: {a.xsd}" + (f" [{a.unit}]" if a.unit else "") for a in args)


def information_model_markdown() -> str:
    """Per asset class: OperationalData properties, then ControlInterface operations."""
    from transfertwin.cps.aas import CONTROL_INTERFACE, OPERATIONAL_DATA

    parts: list[str] = []
    for cls in sorted(set(OPERATIONAL_DATA) | set(CONTROL_INTERFACE)):
        parts += [f"### `{cls}`", ""]
        props = OPERATIONAL_DATA.get(cls, ())
        if props:
            head = "| property | type | unit | initial | kept by | meaning |"
            parts += ["OperationalData:", "", head, "|---|---|---|---|---|---|"]
            for q in props:
                by = "others (external sync)" if q.mixed_external else "the asset"
                parts.append(f"| `{q.id_short}` | `{q.xsd}` | {q.unit or ''} | `{q.initial!r}` "
                             f"| {by} | {q.description} |")  # fmt: skip
            parts.append("")
        ops = CONTROL_INTERFACE.get(cls, ())
        if ops:
            parts += ["ControlInterface:", "", "| operation | inputs | outputs | meaning |",
                      "|---|---|---|---|"]  # fmt: skip
            for o in ops:
                parts.append(f"| `{o.id_short}` | {_args(o.inputs)} | {_args(o.outputs)} "
                             f"| {o.description} |")  # fmt: skip
            parts.append("")
    return "\n".join(parts)


GENERATORS = {
    "<!-- generated:result-columns -->": result_columns_markdown,
    "<!-- generated:profile-settings -->": profile_settings_markdown,
    "<!-- generated:information-model -->": information_model_markdown,
}


def on_page_markdown(markdown: str, **kwargs: object) -> str:
    """Replace each marker line with its generated block."""
    for marker, generate in GENERATORS.items():
        if marker in markdown:
            markdown = markdown.replace(marker, generate())
    return markdown
