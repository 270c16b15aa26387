"""Atomic file writes: every output of boustro is written to a temporary file and renamed.

:func:`atomic_write_all` writes several files as one: every file goes to a temporary file in
its target's folder first, and only when all of them are written are they renamed into place,
so a failure while writing (a full disk, a broken pipe of a network folder) leaves every target
as it was and no temporary file behind. A rename in the same folder does not fail for want of
space; if one still fails (the folder's permissions changed meanwhile), the files not yet
renamed are removed and the error raised, with the earlier targets already replaced.
"""

from __future__ import annotations

import errno
import os
import tempfile
from collections.abc import Iterable

__all__ = ["atomic_write", "atomic_write_all"]


def atomic_write(path: str | os.PathLike[str], data: str | bytes) -> None:
    """Write ``data`` to ``path`` atomically: a temporary file in the same folder, then rename.

    Readers see either the old file or the complete new one; on any error the temporary file
    is removed and ``path`` is left as it was. New files get the usual permissions (umask).
    """
    atomic_write_all([(path, data)])


def atomic_write_all(files: Iterable[tuple[str | os.PathLike[str], str | bytes]]) -> None:
    """Write every ``(path, data)`` of ``files``, all or none (see the module): each to a
    temporary file in its folder, then, once all are written, each renamed into place."""
    targets = [(_target(path), data) for path, data in files]  # every path checked first
    written: list[tuple[str, str]] = []
    try:
        for name, data in targets:
            written.append((_write_temporary(name, data), name))
        while written:
            tmp, name = written[0]
            os.replace(tmp, name)
            written.pop(0)
    except BaseException:
        for tmp, _ in written:
            try:
                os.unlink(tmp)
            except FileNotFoundError:
                pass
        raise


def _target(path: str | os.PathLike[str]) -> str:
    """The file a write of ``path`` replaces (a link's target), or raise if it cannot be one."""
    name = os.fspath(path)
    if os.path.islink(name):  # write the link's target, keep the link
        name = os.path.realpath(name)
    folder = os.path.dirname(os.path.abspath(name))
    if not os.path.isdir(folder):
        raise FileNotFoundError(errno.ENOENT, "no such folder", name)
    if os.path.isdir(name):
        raise IsADirectoryError(errno.EISDIR, "is a folder", name)
    return name


def _write_temporary(name: str, data: str | bytes) -> str:
    """A new temporary file beside ``name`` holding ``data``, flushed to disk, with the
    permissions of ``name`` (or the umask's for a new file); removed on any error."""
    payload = data.encode("utf-8") if isinstance(data, str) else data
    folder = os.path.dirname(os.path.abspath(name))
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
    except BaseException:
        try:
            os.unlink(tmp)
        except FileNotFoundError:
            pass
        raise
    return tmp
