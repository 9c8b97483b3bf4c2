"""One rule for every output path a command is given: checked before any work is done.

A file must end in one of the expected suffixes and live in an existing, writable
directory; a directory must not be a file, and it or its nearest existing ancestor must be a
writable directory. Nothing is created here: commands write their outputs atomically at the end, so
a refused or failed command leaves nothing behind.
"""

from __future__ import annotations

import os
import tempfile
from pathlib import Path

from transfertwin._errors import InputError

__all__ = ["out_dir", "out_file"]


def _writable_dir(path: str, directory: Path) -> None:
    """InputError unless a file can be created in `directory` (probed with a temporary file
    that is removed at once: permission bits alone miss read-only and virtual file systems)."""
    if not directory.exists():
        raise InputError(f"{path}: directory {directory} does not exist")
    if not directory.is_dir():
        raise InputError(f"{path}: {directory} is not a directory")
    try:
        with tempfile.TemporaryFile(dir=directory):
            pass
    except OSError as exc:
        raise InputError(f"{path}: cannot write in {directory}: {exc.strerror}") from None


def out_file(path: str, suffixes: tuple[str, ...]) -> Path:
    """A checked output file path ending in one of `suffixes` (lower-case, with dot)."""
    out = Path(path)
    if out.suffix.lower() not in suffixes:
        raise InputError(f"{path}: expected a file ending in {' or '.join(suffixes)}")
    if out.is_dir():
        raise InputError(f"{path}: is a directory")
    _writable_dir(path, out.parent)
    if out.exists() and not os.access(out, os.W_OK):
        raise InputError(f"{path}: file is not writable")
    return out


def out_dir(path: str) -> Path:
    """A checked output directory path: it may exist, or be creatable below its nearest
    existing ancestor. It is not created here."""
    out = Path(path)
    if out.exists() and not out.is_dir():
        raise InputError(f"{path}: exists and is not a directory")
    ancestor = out
    while not ancestor.exists() and ancestor != ancestor.parent:
        ancestor = ancestor.parent
    _writable_dir(path, ancestor)
    return out
