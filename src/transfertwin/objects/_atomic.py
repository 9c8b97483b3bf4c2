"""Atomic file writes: write a temporary file next to the target, then `os.replace`."""

from __future__ import annotations

import os
import tempfile
from pathlib import Path

__all__ = ["write_bytes_atomic"]


def write_bytes_atomic(path: Path, data: bytes) -> None:
    """Write ``data`` to ``path`` so that readers see either the old or the new file.

    The temporary file lives in the target's directory (same file system), is
    flushed and fsync'ed, then renamed over the target; on any error it is
    removed and no partial file is left behind.

    Args:
        path: Destination file; its directory must exist.
        data: The bytes to write.

    Raises:
        OSError: If the directory is not writable or the disk is full.
    """
    fd, tmp_name = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
    try:
        with os.fdopen(fd, "wb") as handle:
            os.fchmod(handle.fileno(), 0o644)  # mkstemp creates 0o600
            handle.write(data)
            handle.flush()
            os.fsync(handle.fileno())
        os.replace(tmp_name, path)
    except BaseException:
        Path(tmp_name).unlink(missing_ok=True)
        raise
