"""The emulated plant's seed, in a file of its own in the floor's work folder
(``plant.secret``, owner-only): no asset file, status or log holds it."""

from __future__ import annotations

import os
import stat
from pathlib import Path

from transfertwin._errors import InputError

__all__ = ["PLANT_SEED_FILE", "check_plant_seed", "read_plant_seed", "write_plant_seed"]

#: What the plant seed file is called in a floor's work folder.
PLANT_SEED_FILE = "plant.secret"


def write_plant_seed(path: Path, seed: int) -> Path:
    """Write the plant seed to `path`, readable by its owner only."""
    path.parent.mkdir(parents=True, exist_ok=True)
    fd = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_TRUNC, 0o600)
    with os.fdopen(fd, "w") as fh:
        fh.write(f"{int(seed)}\n")
    os.chmod(path, stat.S_IRUSR | stat.S_IWUSR)
    return path


def read_plant_seed(path: Path) -> int:
    """The plant seed in `path` (InputError: missing or not a non-negative integer)."""
    try:
        text = Path(path).read_text().strip()
    except OSError as exc:
        raise InputError(f"{path}: cannot read the plant seed file ({exc.strerror})") from None
    if not text.isdigit():
        raise InputError(f"{path}: the plant seed file must hold a non-negative integer")
    return int(text)


def check_plant_seed(seed: object) -> int:
    """A plant seed as the emulated plant takes it; InputError otherwise."""
    if isinstance(seed, bool) or not isinstance(seed, int) or seed < 0:
        raise InputError(f"--plant-seed must be a non-negative integer, got {seed!r}")
    return seed
