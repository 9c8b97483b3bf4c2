"""The command examples work as written: every line parses, every input exists.

The block of every command (docs/how-to/commands.md) and the README's tour: each `$tt ...`
line must be accepted by the CLI's parser (no `[optional]` brackets pasted into the shell, no
unknown option), and every file or folder it reads must be made by an earlier line (or ship
with the repository): a user who runs a block top to bottom in a fresh clone never meets "no
such file". Running the commands themselves (at small size) is a manual check; this test
keeps the text honest cheaply.
"""

from __future__ import annotations

import re
import shlex
from pathlib import Path

import pytest

from transfertwin._errors import InputError
from transfertwin.cli import build_parser

ROOT = Path(__file__).parents[2]
#: Options whose value is written by the command (the rest are read).
OUTPUT_OPTIONS = {"--out", "--image"}
#: (option, command, subcommand) whose value the command creates.
MAKERS = {("--workdir", "cps", "up"), ("--db", "study", "run")}
PATH_LIKE = re.compile(r"^[\w./-]+(\.(stl|obj|ply|json|csv|sqlite|parquet|toml|aasx|png)|/)$")


COMMANDS_PAGE = ROOT / "docs" / "how-to" / "commands.md"


def command_block() -> list[str]:
    """The lines of the page's command block (continuation lines joined)."""
    text = COMMANDS_PAGE.read_text(encoding="utf-8")
    section = text.split("## Commands", 1)[1]
    block = section.split("```bash", 1)[1].split("```", 1)[0]
    return block.replace("\\\n", " ").splitlines()


def readme_tour() -> list[str]:
    """The lines of every `bash` block in the README's tour of commands."""
    text = (ROOT / "README.md").read_text(encoding="utf-8")
    section = text.split("## A tour", 1)[1].split("\n## ", 1)[0]
    blocks = [b.split("```", 1)[0] for b in section.split("```bash")[1:]]
    return "".join(blocks).replace("\\\n", " ").splitlines()


def commands(lines: list[str] | None = None) -> list[list[str]]:
    """The block's `$tt` commands as argument lists, `for` loops unrolled."""
    out: list[list[str]] = []
    loop: list[str] | None = None
    for line in command_block() if lines is None else lines:
        tokens = shlex.split(line, comments=True)
        if not tokens or tokens[0].startswith("tt="):
            continue
        if tokens[0] == "./dev.sh":
            assert tokens[1] in ("run", "test", "exec"), line
            continue
        if tokens[0] == "for":
            assert tokens[2] == "in" and tokens[-1].endswith("do"), line
            loop = [t.rstrip(";") for t in tokens[3:-1]]
            continue
        assert tokens[0] == "$tt", f"not a transfertwin command: {line!r}"
        args = [t.removesuffix(";") for t in tokens[1:] if t not in ("&", "done")]
        if loop is not None:
            out += [[a.replace("$o", value) for a in args] for value in loop]
            loop = None
        else:
            out.append(args)
    return out


def test_block_has_the_commands() -> None:
    cmds = commands()
    assert len(cmds) > 20
    assert {c[0] for c in cmds} >= {"transfer", "study", "analyze", "calibrate", "cps"}


@pytest.mark.parametrize("args", commands(), ids=lambda a: " ".join(a[:3]))
def test_every_command_parses(args: list[str]) -> None:
    try:
        build_parser().parse_args(args)
    except (InputError, SystemExit) as exc:
        pytest.fail(f"commands.md: `transfertwin {' '.join(args)}` does not parse: {exc}")


def test_the_readme_tours_five_commands_and_they_parse() -> None:
    tour = commands(readme_tour())
    assert [a[0] for a in tour] == ["transfer", "study", "analyze", "calibrate", "web"], tour
    for args in tour:
        try:
            build_parser().parse_args(args)
        except (InputError, SystemExit) as exc:
            pytest.fail(f"README: `transfertwin {' '.join(args)}` does not parse: {exc}")


@pytest.mark.parametrize("where", ["commands.md", "README"])
def test_every_input_is_made_by_an_earlier_command(where: str) -> None:
    made: set[str] = set()
    for args in commands() if where == "commands.md" else commands(readme_tour()):
        reads = []
        for i, token in enumerate(args):
            before = args[i - 1] if i else ""
            if (before, *args[:2]) in MAKERS or before in OUTPUT_OPTIONS:
                made.add(token)
            elif PATH_LIKE.match(token) and not token.startswith("-"):
                reads.append(token)
        for path in reads:
            inside = any(path.startswith(m) for m in made if m.endswith("/"))
            assert path in made or inside or (ROOT / path).exists(), (
                f"{where}: `transfertwin {' '.join(args)}` reads {path}, "
                "which no earlier command makes"
            )


def test_a_study_db_is_not_reused_for_another_plan() -> None:
    """`study run` refuses a different plan on an existing db: the block must not try."""
    plans: dict[str, list[str]] = {}
    ignore = {"--workers", "--max-experiments"}
    for args in commands():
        if args[:2] != ["study", "run"]:
            continue
        db = args[args.index("--db") + 1]
        plan = [a for i, a in enumerate(args) if a not in ignore and args[i - 1] not in ignore]
        assert plans.setdefault(db, plan) == plan, f"commands.md: {db} is reused for another plan"
