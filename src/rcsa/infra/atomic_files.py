"""Durable file writes: fsync helpers and write-to-temporary-then-rename.

Every file rcsa keeps (measurements, cached results, keys, markers, exports) is written
under a temporary name in the same directory, flushed and fsynced, then ``os.replace``d
into place and the directory fsynced, so a crash leaves either the old file or the new one,
never a torn one (``docs/architecture.md`` "Durable storage").
"""

from __future__ import annotations

import contextlib
import errno
import os
import secrets
from pathlib import Path

__all__ = ["atomic_write_bytes", "fsync_dir", "fsync_file"]


def fsync_file(path: str | os.PathLike[str]) -> None:
    """Flush a closed file's data to stable storage (``os.fsync``)."""
    fd = os.open(path, os.O_RDONLY)
    try:
        os.fsync(fd)
    finally:
        os.close(fd)


def fsync_dir(path: str | os.PathLike[str]) -> None:
    """Make a rename in ``path`` durable; a no-op where directories cannot be fsynced."""
    try:
        fd = os.open(path, os.O_RDONLY)
    except OSError:  # e.g. Windows: directories cannot be opened
        return
    try:
        os.fsync(fd)
    except OSError as e:
        if e.errno not in (errno.EINVAL, errno.ENOTSUP, errno.EBADF):
            raise
    finally:
        os.close(fd)


def atomic_write_bytes(path: str | os.PathLike[str], data: bytes, *, mode: int = 0o644) -> None:
    """Replace ``path`` with ``data`` atomically and durably.

    Parameters
    ----------
    path : path-like
        Final name; its directory must exist.
    data : bytes
    mode : int
        Permissions of the new file (e.g. ``0o600`` for secrets' hashes).

    Raises
    ------
    OSError
        When the file cannot be written; the temporary file is removed and ``path`` is
        left as it was.
    """
    final = Path(path)
    tmp = final.with_name(f".{final.name}.{os.getpid()}.{secrets.token_hex(4)}.tmp")
    try:
        fd = os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_EXCL, mode)
        with os.fdopen(fd, "wb") as fh:
            fh.write(data)
            fh.flush()
            os.fsync(fh.fileno())
        os.replace(tmp, final)
    except OSError:
        with contextlib.suppress(OSError):
            tmp.unlink()
        raise
    fsync_dir(final.parent)
