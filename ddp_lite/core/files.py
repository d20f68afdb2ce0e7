"""Generic file helpers every writer and reader of the kit shares, the downloader included.

- Atomic writes (:func:`atomic_path`, :func:`write_bytes_atomic`): write a temporary file next to
  the target, then rename it over the target. A reader never sees a half-written file, and a failed
  or interrupted write leaves the old file (or no file) behind, never a truncated one. The rename is
  atomic because the temporary file is in the target's own folder (same file system). The new file
  gets the mode a plain ``open`` would give it (``0o666`` less the umask), or, when it replaces a
  file, that file's mode. A read-only target is refused unless ``overwrite_readonly``.
- The one path guard (:func:`path_inside`): a name that must stay inside a folder (a dataset's
  file under the data root, a file a command writes into its output folder) is refused when it is
  absolute, climbs out with ``..``, or passes through a symbolic link on the way (a sub-folder of an
  output folder linked to the user's own files would have them overwritten). Every atomic write
  made inside :func:`writing_inside` (``ddp_lite.core.outpaths.output_lock`` enters it for every
  output folder) goes through it, so no writer writes through a link inside its output folder.
- The one way every text file is read (:func:`read_text`, :func:`decode_text`): UTF-8, or UTF-16 with
  its byte-order mark; a UTF-8 byte-order mark dropped; CRLF and CR line ends made LF. Editors on
  Windows save a ``dmin.txt`` or ``calib.txt`` that way; its numbers are the same numbers.
- The one check every reader of a user's file makes first (:func:`regular_file`): the path names an
  existing *regular* file. A FIFO, a device or a socket under a file's name makes a reader block
  forever (hashing a FIFO waits for a writer that never comes) or read endless bytes; a folder where
  a file is expected fails later with an error that names neither. It refuses all of them before a
  byte is read, naming the argument the path came from.

Standard library only, so ``data_fetch`` (which imports it from here) runs without torch.

Example:
    >>> import tempfile, os
    >>> folder = tempfile.mkdtemp()
    >>> regular_file(folder, "path")
    Traceback (most recent call last):
    ...
    IsADirectoryError: path: ... is a folder; expected a file
"""
from __future__ import annotations

import contextlib
import contextvars
import os
import stat
import tempfile
from pathlib import Path

__all__ = ["atomic_path", "write_bytes_atomic", "replace_between_markers", "regular_file", "read_regular_bytes", "read_text", "decode_text",
           "NotTextError", "describe_kind", "path_inside", "writing_inside", "PathEscapeError"]


class PathEscapeError(ValueError):
    """A path that was to stay inside a folder leads out of it (absolute, ``..``, a symbolic link)."""


def path_inside(root, name, what: str = "name", links: bool = False) -> Path:
    """``root / name`` if it stays inside ``root``; else :class:`PathEscapeError` naming ``what``.

    Refused: an empty or absolute ``name``, a ``..`` in it, and a symbolic link on the way below
    ``root`` (the link itself or a folder on the way): with ``links=False`` any such link (a writer
    must not write through one), with ``links=True`` only one whose target resolves outside ``root``.
    ``root`` itself may be a link (the user's choice of folder)."""
    text = os.fspath(name)
    parts = Path(text).parts
    if not text or not parts or os.path.isabs(text) or Path(text).drive or ".." in parts:
        raise PathEscapeError(f"{what}: {text!r} must be a relative path inside {os.fspath(root)} (no leading "
                              f"'/', no '..'); refusing to touch a file outside it")
    root = Path(os.path.abspath(os.fspath(root)))
    real_root = os.path.realpath(root)
    here = root
    for part in parts:
        here = here / part
        if os.path.islink(here):
            real = os.path.realpath(here)
            if not links or os.path.commonpath([real, real_root]) != real_root:
                raise PathEscapeError(f"{what}: {here} is a symbolic link to {real}; refusing to write or read "
                                      f"through it (it leads out of {root}); remove the link or choose another "
                                      f"folder")
    return root.joinpath(*parts)


_OUTPUT_ROOTS: contextvars.ContextVar = contextvars.ContextVar("ddp_lite_output_roots", default=())


@contextlib.contextmanager
def writing_inside(*roots):
    """Inside the block, every :func:`atomic_path` (so every writer of the kit) whose target lies under
    one of ``roots`` refuses a symbolic link on its way below that root (:func:`path_inside`)."""
    added = tuple(os.path.abspath(os.fspath(r)) for r in roots)
    token = _OUTPUT_ROOTS.set(_OUTPUT_ROOTS.get() + added)
    try:
        yield
    finally:
        _OUTPUT_ROOTS.reset(token)


def _check_roots(path: str) -> None:
    for root in _OUTPUT_ROOTS.get():
        if path != root and os.path.commonpath([path, root]) == root:
            path_inside(root, os.path.relpath(path, root), "output")


def _umask() -> int:
    try:  # Linux: read it without changing it
        with open("/proc/self/status") as status:
            for line in status:
                if line.startswith("Umask:"):
                    return int(line.split()[1], 8)
    except (OSError, ValueError):
        pass
    mask = os.umask(0o022)
    os.umask(mask)
    return mask


@contextlib.contextmanager
def atomic_path(path, suffix: str | None = None, overwrite_readonly: bool = False, prefix: str = ".tmp-"):
    """Yield a temporary path next to ``path``; on success it replaces ``path``, on error it is removed.

    Args:
        path: the file to write (str or ``os.PathLike``); its folder is created if missing.
        suffix: the temporary file's ending; default ``path``'s own. Writers that pick the format
            from the name (Open3D, Matplotlib) need the real one.
        overwrite_readonly: replace ``path`` even if it is read-only (no write bit); else
            ``PermissionError`` before anything is written.
        prefix: the temporary file's name starts with it: a writer that sweeps up what a killed run left
            (``data_fetch``) gives its own, so it recognises its temporaries and no one else's.

    Example:
        >>> import numpy as np, tempfile, os
        >>> target = os.path.join(tempfile.mkdtemp(), "depth.npy")
        >>> with atomic_path(target) as tmp, open(tmp, "wb") as handle:
        ...     np.save(handle, np.zeros(3))
        >>> np.load(target).shape
        (3,)
    """
    path = os.path.abspath(os.fspath(path))
    _check_roots(path)  # no symbolic link inside an output folder on the way
    if os.path.isdir(path):
        raise IsADirectoryError(f"{path} is a folder; give a file name")
    mode = 0o666 & ~_umask()
    if os.path.exists(path):
        mode = stat.S_IMODE(os.stat(path).st_mode)
        if not mode & 0o222 and not overwrite_readonly:
            raise PermissionError(f"{path} is read-only; refusing to replace it (make it writable, or force)")
    directory = os.path.dirname(path)
    os.makedirs(directory, exist_ok=True)
    suffix = os.path.splitext(path)[1] if suffix is None else suffix
    fd, tmp = tempfile.mkstemp(dir=directory, prefix=prefix, suffix=suffix)
    os.close(fd)
    os.chmod(tmp, mode)
    try:
        yield tmp
        os.replace(tmp, path)
    except BaseException:
        if os.path.exists(tmp):
            os.remove(tmp)
        raise


def write_bytes_atomic(path, data: bytes, overwrite_readonly: bool = False, prefix: str = ".tmp-") -> None:
    """Write ``data`` to ``path`` atomically (``prefix``: see :func:`atomic_path`)."""
    view = memoryview(data).cast("B")
    with atomic_path(path, overwrite_readonly=overwrite_readonly, prefix=prefix) as tmp:
        fd = os.open(tmp, os.O_WRONLY | os.O_TRUNC)
        try:
            while view:  # os.write may write less than it was given
                view = view[os.write(fd, view):]
        finally:
            os.close(fd)


def replace_between_markers(path, start: str, end: str, body: str, what: str = "table") -> bool:
    """Put ``body`` between the lines ``start`` and ``end`` of the UTF-8 text file ``path`` (a generated table in a
    README), atomically; True if the file changed. ``ValueError`` naming ``path`` when a marker is missing."""
    text = Path(path).read_text(encoding="utf-8")
    if start not in text or end not in text:
        raise ValueError(f"readme {str(path)!r} has no {what} markers ({start} ... {end})")
    head, rest = text.split(start, 1)
    _, tail = rest.split(end, 1)
    new = f"{head}{start}\n{body}\n{end}{tail}"
    if new != text:
        write_bytes_atomic(path, new.encode("utf-8"))
    return new != text


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


def read_regular_bytes(path, name: str = "path", links: bool = True) -> bytes:
    """The bytes of ``path``, opened so that only a regular file is ever read: the open cannot block on a
    FIFO (``O_NONBLOCK``) and the file opened is the one checked (``fstat`` on the open descriptor, so a
    file swapped for a FIFO, a device or a socket between a check and the read is refused, not read).
    ``links=False`` refuses a symbolic link as well (``O_NOFOLLOW``).

    Raises ``FileNotFoundError``, ``IsADirectoryError`` or ``ValueError`` (a FIFO, a device, a socket, a
    refused link), each naming ``name`` and the path."""
    flags = os.O_RDONLY | os.O_NONBLOCK | getattr(os, "O_CLOEXEC", 0) | (0 if links else getattr(os, "O_NOFOLLOW", 0))
    try:
        fd = os.open(path, flags)
    except FileNotFoundError:
        raise FileNotFoundError(f"{name}: {path} does not exist") from None
    except IsADirectoryError:
        raise IsADirectoryError(f"{name}: {path} is a folder; expected a file") from None
    except OSError as error:
        if not links and os.path.islink(path):
            raise ValueError(f"{name}: {path} is a symbolic link; refusing to follow it") from None
        raise
    try:
        mode = os.fstat(fd).st_mode
        if stat.S_ISDIR(mode):
            raise IsADirectoryError(f"{name}: {path} is a folder; expected a file")
        if not stat.S_ISREG(mode):
            raise ValueError(f"{name}: {path} is {describe_kind(mode)}, not a regular file; refusing to read it "
                             f"(a reader would block or read without end)")
        os.set_blocking(fd, True)
        chunks = []
        while chunk := os.read(fd, 1 << 20):
            chunks.append(chunk)
        return b"".join(chunks)
    finally:
        os.close(fd)


class NotTextError(ValueError):
    """A file read as text is not text (not UTF-8 or UTF-16 with a byte-order mark, or holds NUL bytes)."""


def decode_text(data: bytes, path, name: str = "path") -> str:
    """A text file's bytes → its text, normalised: UTF-8 (a leading UTF-8 byte-order mark dropped) or UTF-16
    with its byte-order mark; ``\\r\\n`` and a lone ``\\r`` become ``\\n``. Anything else (another encoding,
    NUL bytes: a binary file) → :class:`NotTextError` naming ``name`` and ``path``."""
    try:
        if data.startswith((b"\xff\xfe", b"\xfe\xff")):  # UTF-16 with its BOM (Windows editors' "Unicode")
            text = data.decode("utf-16")
        else:
            text = data.decode("utf-8-sig")
    except UnicodeDecodeError as error:
        raise NotTextError(f"{name}: {path} is not a UTF-8 text file (byte {error.start} is not UTF-8, and it "
                           f"starts with no UTF-16 byte-order mark); is it the right file?") from None
    if "\x00" in text:
        raise NotTextError(f"{name}: {path} holds NUL bytes: a binary file, not text; is it the right file?")
    return text.replace("\r\n", "\n").replace("\r", "\n")


def read_text(path, name: str = "path") -> str:
    """The text of the regular file ``path``, as :func:`decode_text` normalises it; errors name ``name``."""
    return decode_text(read_regular_bytes(path, name), path, name)
