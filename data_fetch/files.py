"""The one check every reader of a user's file makes first: the path names an existing *regular* file.

A FIFO, a device or a socket under a file's name makes a reader block forever (hashing a FIFO
waits for a writer that never comes) or read endless bytes; a folder where a file is expected
fails later with an error that names neither. :func:`regular_file` refuses all of them before a
byte is read, naming the argument the path came from. Standard library only, so ``data_fetch``
uses it without torch; ``ddp_lite.data.fileio`` re-exports it for the kit's readers.

Example:
    >>> import tempfile, os
    >>> folder = tempfile.mkdtemp()
    >>> regular_file(folder, "path")
    Traceback (most recent call last):
    ...
    IsADirectoryError: path: ... is a folder; expected a file
"""
from __future__ import annotations

import os
import stat
from pathlib import Path

__all__ = ["regular_file", "describe_kind"]


def describe_kind(mode: int) -> str:
    """What a ``st_mode`` is, in words: 'a file', 'a folder', 'a FIFO (named pipe)', 'a character device', ..."""
    for test, words in ((stat.S_ISREG, "a file"), (stat.S_ISDIR, "a folder"), (stat.S_ISFIFO, "a FIFO (named pipe)"),
                        (stat.S_ISCHR, "a character device"), (stat.S_ISBLK, "a block device"),
                        (stat.S_ISSOCK, "a socket")):
        if test(mode):
            return words
    return "not a regular file"


def regular_file(path, name: str = "path") -> Path:
    """``path`` as a ``Path`` if it names an existing regular file (a symlink to one is fine).

    Raises ``FileNotFoundError`` (missing), ``IsADirectoryError`` (a folder) or ``ValueError``
    (a FIFO, device or socket), each naming ``name`` and the path, before anything is opened."""
    path = Path(path)
    try:
        mode = os.stat(path).st_mode  # follows symlinks: what a reader would open
    except FileNotFoundError:
        raise FileNotFoundError(f"{name}: {path} does not exist") from None
    except NotADirectoryError:
        raise FileNotFoundError(f"{name}: {path} does not exist (a part of it is a file, not a folder)") from None
    if stat.S_ISREG(mode):
        return path
    if stat.S_ISDIR(mode):
        raise IsADirectoryError(f"{name}: {path} is a folder; expected a file")
    raise ValueError(f"{name}: {path} is {describe_kind(mode)}, not a regular file; refusing to read it "
                     f"(a reader would block or read without end)")
