"""The command reference, docs/reference/cli.md, is the one the CLI's parser prints.

`scripts/cli_reference.py` writes every command's `--help` into the page; this test fails
when an option, a subcommand or a help text changed without the page being written again.
"""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).parents[2]
SCRIPT = ROOT / "scripts" / "cli_reference.py"


def test_the_command_reference_is_generated_from_the_parser() -> None:
    check = subprocess.run(
        [sys.executable, str(SCRIPT), "--check"], check=False, capture_output=True, text=True
    )
    assert check.returncode == 0, f"{check.stdout}run: python scripts/cli_reference.py --write"


def test_every_command_has_a_section() -> None:
    page = (ROOT / "docs" / "reference" / "cli.md").read_text(encoding="utf-8")
    for command in ("transfer", "study run", "analyze", "calibrate tune", "cps up", "web"):
        assert f"transfertwin {command}\n" in page, command
