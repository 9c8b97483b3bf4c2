"""The vocabulary of docs/reference/information-model.md is the one the ontology defines.

`scripts/information_model.py` writes every concept an AAS names into the page; this test
fails when the ontology changed without the page being written again.
"""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).parents[3]
SCRIPT = ROOT / "scripts" / "information_model.py"
PAGE = ROOT / "docs" / "reference" / "information-model.md"


def test_the_vocabulary_is_generated_from_the_ontology() -> None:
    check = subprocess.run(
        [sys.executable, str(SCRIPT), "--check"], check=False, capture_output=True, text=True
    )
    assert check.returncode == 0, f"{check.stdout}run: python scripts/information_model.py --write"


def test_the_page_defines_the_concepts_an_aas_names() -> None:
    page = PAGE.read_text(encoding="utf-8")
    rows = (
        "| `tt:BeltWidth` | belt width | Width of one belt. | transfer unit, transport module |",
        "| `tt:realizedBy` | realized by |",
        "| `tt:TransferHistoryJson` |",
        "### State variable (`tt:StateVariable`)",
    )
    for row in rows:
        assert row in page, row
