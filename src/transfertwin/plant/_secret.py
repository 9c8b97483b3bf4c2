"""An emulated plant's seed, in a file of its own (``plant.secret``, owner-only).

The seed draws every hidden value of the plant, so it is kept out of every record a
rehearsal writes (``rehearsal.json`` names the plant's kind, not its seed): `rehearse`
writes it beside them, and what needs the plant again (a replay of its rows, the oracle
benchmarks) reads it from there.
"""

from __future__ import annotations

import os
import stat
from pathlib import Path

from transfertwin._errors import InputError

__all__ = ["PLANT_SEED_FILE", "read_plant_seed", "write_plant_seed"]

#: What the plant seed file is called beside a rehearsal's ``rehearsal.json``.
PLANT_SEED_FILE = "plant.secret"


def write_plant_seed(path: str | Path, seed: int) -> Path:
    """Write the plant seed to `path`, readable and writable by its owner only (0600)."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_TRUNC, 0o600)
    with os.fdopen(fd, "w", encoding="utf-8") as fh:
        fh.write(f"{int(seed)}\n")
    os.chmod(path, stat.S_IRUSR | stat.S_IWUSR)
    return path


def read_plant_seed(path: str | Path) -> int:
    """The plant seed in `path` (InputError: unreadable or not a non-negative integer)."""
    try:
        text = Path(path).read_text(encoding="utf-8").strip()
    except (OSError, UnicodeDecodeError) as exc:
        raise InputError(f"{path}: cannot read the plant seed file ({exc})") from None
    if not text.isdigit():
        raise InputError(f"{path}: the plant seed file must hold a non-negative integer")
    return int(text)
