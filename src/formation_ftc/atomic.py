"""The package's one atomic file write: a reader sees the old file or the whole new one, never a part.

The data goes to a temporary file in the target's directory (``.NAME.tmp-PID``, a name every directory
scan of the package skips), is flushed to disk (``fsync``) and renamed over the target with
:func:`os.replace` (atomic on POSIX and Windows); the directory entry is then synced, best effort.
On any failure -- a full disk (``ENOSPC``) included, or an interrupt -- the temporary file is removed
and the error propagates; the target keeps its previous content.

Examples
--------
>>> import tempfile, pathlib
>>> p = pathlib.Path(tempfile.mkdtemp()) / "a.txt"
>>> _ = atomic_write(p, "one")
>>> _ = atomic_write(p, b"two")
>>> p.read_text(), [q.name for q in p.parent.iterdir()]
('two', ['a.txt'])
"""

from __future__ import annotations

import errno
import os
from collections.abc import Callable
from pathlib import Path

__all__ = ["atomic_write", "temporary_name"]


def temporary_name(path: Path | str) -> Path:
    """Where :func:`atomic_write` puts ``path``'s data before the rename (``.NAME.tmp-PID``)."""
    path = Path(path)
    return path.with_name(f".{path.name}.tmp-{os.getpid()}")


def _fsync_dir(directory: Path) -> None:
    """Make a rename in ``directory`` durable (best effort: not every platform has directory fds)."""
    try:
        fd = os.open(directory, os.O_RDONLY)
    except OSError:  # pragma: no cover - e.g. Windows
        return
    try:
        os.fsync(fd)
    except OSError:  # pragma: no cover - a file system without directory sync
        pass
    finally:
        os.close(fd)


def atomic_write(
    path: Path | str, data: bytes | str | Callable[[Path], object], *, encoding: str = "utf-8"
) -> Path:
    """Replace ``path`` with ``data`` atomically; returns ``path``.

    Parameters
    ----------
    path : Path or str
        The target file; its directory must exist.
    data : bytes, str or callable
        The new content (``str`` is encoded with ``encoding``), or a function that writes the file
        whose path it is given (e.g. ``lambda p: dataset.to_netcdf(p)``).
    encoding : str
        Text encoding of a ``str``.

    Raises
    ------
    OSError
        When the data cannot be written, synced or renamed: ``path`` is unchanged and no temporary
        file is left behind; a full disk (``ENOSPC``, ``EDQUOT``) is reported with ``path`` as its
        file name.
    """
    path = Path(path)
    tmp = temporary_name(path)
    try:
        if callable(data):
            data(tmp)
            with open(tmp, "rb+") as f:
                os.fsync(f.fileno())
        else:
            with open(tmp, "wb") as f:
                f.write(data.encode(encoding) if isinstance(data, str) else data)
                f.flush()
                os.fsync(f.fileno())
        os.replace(tmp, path)
    except BaseException as exc:
        tmp.unlink(missing_ok=True)
        if isinstance(exc, OSError) and exc.errno in (errno.ENOSPC, errno.EDQUOT):
            # a full disk names the target, not the temporary file (exit status 3, one line)
            raise OSError(exc.errno, exc.strerror, str(path)) from None
        raise
    _fsync_dir(path.parent)
    return path
