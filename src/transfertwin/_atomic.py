"""Atomic file writes shared by every layer (stdlib only, like `_errors`).

A temporary file is written next to the target, flushed and fsync'ed, then renamed over it
(`write_atomic`) or hard-linked to it (`write_bytes_exclusive`, first writer wins), so
readers see the old file or the whole new one, never a part. `file_stamp` tells a file
rewritten in place (or renamed over, as here) from the one a cache read.
"""

from __future__ import annotations

import os
import tempfile
from pathlib import Path

__all__ = ["file_stamp", "write_atomic", "write_bytes_atomic", "write_bytes_exclusive"]


def _temporary_copy(path: Path, data: bytes, mode: int = 0o644) -> Path:
    """Write ``data`` to a flushed, fsync'ed temporary file in ``path``'s directory."""
    fd, name = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
    try:
        with os.fdopen(fd, "wb") as handle:
            os.fchmod(handle.fileno(), mode)  # mkstemp creates 0o600
            handle.write(data)
            handle.flush()
            os.fsync(handle.fileno())
    except BaseException:
        Path(name).unlink(missing_ok=True)
        raise
    return Path(name)


def write_bytes_atomic(path: Path, data: bytes, mode: int = 0o644) -> None:
    """Write ``data`` to ``path`` so that readers see either the old or the new file.

    The temporary file lives in the target's directory (same file system) and
    is renamed over the target with `os.replace`; on any error it is removed
    and no partial file is left behind.

    Args:
        path: Destination file; its directory must exist.
        data: The bytes to write.
        mode: Permission bits of the new file.

    Raises:
        OSError: If the directory is not writable or the disk is full.
    """
    tmp = _temporary_copy(path, data, mode)
    try:
        os.replace(tmp, path)
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise


def write_bytes_exclusive(path: Path, data: bytes) -> bool:
    """Create ``path`` with ``data`` atomically unless it exists (first writer wins).

    The complete temporary file is hard-linked to ``path``, which fails if
    ``path`` exists, so concurrent writers never replace each other's file.
    Where hard links are unsupported it falls back to `write_bytes_atomic`.

    Args:
        path: Destination file; its directory must exist.
        data: The bytes to write.

    Returns:
        True if this call created ``path``, False if it already existed.

    Raises:
        OSError: If the directory is not writable or the disk is full.
    """
    tmp = _temporary_copy(path, data)
    try:
        os.link(tmp, path)
    except FileExistsError:
        return False
    except OSError:
        os.replace(tmp, path)
        return True
    finally:
        tmp.unlink(missing_ok=True)
    return True


def write_atomic(path: str | Path, data: bytes | str, mode: int = 0o644) -> Path:
    """`write_bytes_atomic` for text (UTF-8) or bytes with file `mode`; returns the path.

    The mode is set on the temporary file before any data is written, so a secret written
    with mode 0o600 is never readable by others, not even for a moment. Missing parent
    directories are created (outputs are written last, once their content is known).
    """
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    write_bytes_atomic(path, data.encode("utf-8") if isinstance(data, str) else data, mode)
    return path


def file_stamp(path: str | os.PathLike[str]) -> tuple[int, int, int] | None:
    """(inode, size, modification time in ns) of the file at `path`, None where there is
    none: a cache keyed by it loads a rewritten file again."""
    try:
        st = os.stat(path)
    except OSError:
        return None
    return (st.st_ino, st.st_size, st.st_mtime_ns)
