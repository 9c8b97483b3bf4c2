"""The emulated plant's seed, in a file of its own in the floor's work folder
(``plant.secret``, owner-only): no asset file, status or log holds it. The file names the
plant's kind after the seed when it is not the in-class plant (``7 mismatch``), and after
the kind the mismatch parts switched off, if any (``7 mismatch off=contact,sag``, an
ablation): the seed, the kind and the parts together are the plant."""

from __future__ import annotations

import os
import stat
from pathlib import Path

from transfertwin._errors import InputError

__all__ = ["PLANT_SEED_FILE", "check_plant_seed", "read_plant_kind", "read_plant_off",
           "read_plant_seed", "write_plant_seed"]  # fmt: skip

#: What the plant seed file is called in a floor's work folder.
PLANT_SEED_FILE = "plant.secret"


def write_plant_seed(path: Path, seed: int, kind: str = "in-class",
                     mismatch_off: tuple[str, ...] = ()) -> Path:  # fmt: skip
    """Write the plant seed (a kind other than 'in-class', the mismatch parts switched
    off) to `path`, readable by its owner only."""
    words = [str(int(seed))]
    if kind != "in-class" or mismatch_off:
        words.append(kind)
    if mismatch_off:
        words.append("off=" + ",".join(sorted(mismatch_off)))
    path.parent.mkdir(parents=True, exist_ok=True)
    fd = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_TRUNC, 0o600)
    with os.fdopen(fd, "w") as fh:
        fh.write(" ".join(words) + "\n")
    os.chmod(path, stat.S_IRUSR | stat.S_IWUSR)
    return path


def _read(path: Path) -> tuple[int, str, tuple[str, ...]]:
    try:
        words = Path(path).read_text().split()
    except OSError as exc:
        raise InputError(f"{path}: cannot read the plant seed file ({exc.strerror})") from None
    if not 1 <= len(words) <= 3 or not words[0].isdigit() \
            or (len(words) == 3 and not words[2].startswith("off=")):  # fmt: skip
        raise InputError(f"{path}: the plant seed file must hold a non-negative integer "
                         "(optionally the plant's kind after it, then off=PART,...)")  # fmt: skip
    off = tuple(p for p in words[2].removeprefix("off=").split(",") if p) if len(words) == 3 else ()
    return int(words[0]), words[1] if len(words) >= 2 else "in-class", off


def read_plant_seed(path: Path) -> int:
    """The plant seed in `path` (InputError: missing or not a non-negative integer)."""
    return _read(path)[0]


def read_plant_kind(path: Path) -> str:
    """The plant's kind in `path`: 'in-class' unless the file names another after the
    seed (checked where the plant is made)."""
    return _read(path)[1]


def read_plant_off(path: Path) -> tuple[str, ...]:
    """The mismatch parts switched off on the plant in `path` (none: the whole mismatch)."""
    return _read(path)[2]


def check_plant_seed(seed: object) -> int:
    """A plant seed as the emulated plant takes it; InputError otherwise."""
    if isinstance(seed, bool) or not isinstance(seed, int) or seed < 0:
        raise InputError(f"--plant-seed must be a non-negative integer, got {seed!r}")
    return seed
