"""Atomic file writes: write a temporary file next to the target, then rename it over the target.

A reader never sees a half-written file, and a failed or interrupted write leaves the old file
(or no file) behind, never a truncated one. The rename is atomic because the temporary file is
in the target's own folder (same file system).
"""
from __future__ import annotations

import contextlib
import os
import tempfile

__all__ = ["atomic_path", "write_bytes_atomic"]


@contextlib.contextmanager
def atomic_path(path, suffix: str | None = None):
    """Yield a temporary path next to ``path``; on success it replaces ``path``, on error it is removed.

    Args:
        path: the file to write (str or ``os.PathLike``); its folder is created if missing.
        suffix: the temporary file's ending; default ``path``'s own. Writers that pick the format
            from the name (Open3D, Matplotlib) need the real one.

    Example:
        >>> import numpy as np, tempfile, os
        >>> target = os.path.join(tempfile.mkdtemp(), "depth.npy")
        >>> with atomic_path(target) as tmp, open(tmp, "wb") as handle:
        ...     np.save(handle, np.zeros(3))
        >>> np.load(target).shape
        (3,)
    """
    path = os.path.abspath(os.fspath(path))
    directory = os.path.dirname(path)
    os.makedirs(directory, exist_ok=True)
    suffix = os.path.splitext(path)[1] if suffix is None else suffix
    fd, tmp = tempfile.mkstemp(dir=directory, prefix=".tmp-", suffix=suffix)
    os.close(fd)
    try:
        yield tmp
        os.replace(tmp, path)
    except BaseException:
        if os.path.exists(tmp):
            os.remove(tmp)
        raise


def write_bytes_atomic(path, data: bytes) -> None:
    """Write ``data`` to ``path`` atomically."""
    with atomic_path(path) as tmp, open(tmp, "wb") as handle:
        handle.write(data)
