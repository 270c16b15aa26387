"""Atomic file writes: every output of boustro is written to a temporary file and renamed."""

from __future__ import annotations

import errno
import os
import tempfile

__all__ = ["atomic_write"]


def atomic_write(path: str | os.PathLike[str], data: str | bytes) -> None:
    """Write ``data`` to ``path`` atomically: a temporary file in the same folder, then rename.

    Readers see either the old file or the complete new one; on any error the temporary file
    is removed and ``path`` is left as it was. New files get the usual permissions (umask).
    """
    name = os.fspath(path)
    if os.path.islink(name):  # write the link's target, keep the link
        name = os.path.realpath(name)
    folder = os.path.dirname(os.path.abspath(name))
    if not os.path.isdir(folder):
        raise FileNotFoundError(errno.ENOENT, "no such folder", name)
    if os.path.isdir(name):
        raise IsADirectoryError(errno.EISDIR, "is a folder", name)
    payload = data.encode("utf-8") if isinstance(data, str) else data
    fd, tmp = tempfile.mkstemp(prefix=f".{os.path.basename(name)}.", suffix=".tmp", dir=folder)
    try:
        with os.fdopen(fd, "wb") as fh:
            fh.write(payload)
            fh.flush()
            os.fsync(fh.fileno())
        try:
            mode = os.stat(name).st_mode & 0o777
        except FileNotFoundError:
            umask = os.umask(0)
            os.umask(umask)
            mode = 0o666 & ~umask
        os.chmod(tmp, mode)
        os.replace(tmp, name)
    except BaseException:
        try:
            os.unlink(tmp)
        except FileNotFoundError:
            pass
        raise
