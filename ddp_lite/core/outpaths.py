"""Output paths (of the command line and the classroom kit), checked before any work starts.

A command that renders for minutes and then finds it cannot write its result has wasted those
minutes; one that writes its output over its own input has lost the input. Every ``--out``-like
flag goes through one of these checks first; each raises ``ValueError`` naming the flag.

Writing them: :func:`output_set` stages every file of one command's output (a depth and its
preview, a view's files and the manifest) beside its target and renames them all at the end, with
SIGTERM and SIGINT held back during the renames, under :func:`output_lock`, a lock file per target
created with ``O_EXCL``: a second command writing any of the same files is refused with a message
naming the first (a lock whose process is gone is taken over). So a failure (a full disk, an error,
SIGTERM, which raises ``KeyboardInterrupt`` inside the block) leaves every old file as it was and no
temporary file behind, and two commands never leave a mix of their outputs. What it does not give:
a SIGKILL or a power cut during the renames can still leave part of the set renamed.
"""
from __future__ import annotations

import contextlib
import json
import os
import signal
import socket
import tempfile
import threading
import time

from .files import atomic_path, writing_inside

__all__ = ["check_output_file", "check_output_folder", "check_not_overlapping", "output_lock", "output_set",
           "lock_path"]

LOCK_NAME = ".ddp-lite.lock"


def _existing_ancestor(path: str) -> str:
    folder = path
    while not os.path.exists(folder):
        folder = os.path.dirname(folder)
    return folder


def _check_writable_folder(folder: str, flag: str, given) -> None:
    """``folder`` exists: refuse it unless it is a folder a file can be created in."""
    if not os.path.isdir(folder):
        raise ValueError(f"{flag} {given!r}: {folder} is a file, not a folder")
    try:  # the one sure test (permissions, read-only mounts, quotas): create a file there
        fd, probe = tempfile.mkstemp(dir=folder, prefix=".ddp-lite-probe-")
    except OSError as error:
        raise ValueError(f"{flag} {given!r}: cannot write in {folder} ({error.strerror})") from None
    os.close(fd)
    os.remove(probe)


def check_output_file(path, flag: str, suffixes=None, inputs: dict | None = None, force: bool = False,
                      example: str = "out.png") -> str:
    """Refuse an output file that cannot or must not be written; return its absolute path.

    Args:
        path: the file the command will write (str or ``os.PathLike``).
        flag: the option's name for messages, e.g. ``"--out"``.
        suffixes: the accepted endings (lower case, with the dot), or None for any.
        inputs: ``{flag: path}`` of the command's inputs; the output must not be one of them.
        force: accept a read-only existing file (the command will replace it).
        example: a file name to suggest when ``path`` is a folder.

    Raises:
        ValueError: ``path`` is a folder, has another suffix, is an input, is read-only (without
            ``force``), lies under a file, or its folder is not writable.
    """
    given = os.fspath(path)
    out = os.path.abspath(given)
    if os.path.isdir(out) or given.endswith(tuple(filter(None, (os.sep, os.altsep, "/")))):
        raise ValueError(f"{flag} {given!r} is a folder (or ends in a '/'); give a file name such as {example}")
    suffix = os.path.splitext(out)[1].lower()
    if suffixes is not None and suffix not in suffixes:
        raise ValueError(f"{flag} must end in {', '.join(sorted(suffixes))} (the format follows the suffix), "
                         f"got {given!r}")
    for input_flag, input_path in (inputs or {}).items():
        input_path = os.fspath(input_path)
        if os.path.abspath(input_path) == out or (os.path.exists(out) and os.path.exists(input_path)
                                                  and os.path.samefile(input_path, out)):
            raise ValueError(f"{flag} is the same file as {input_flag} ({input_path!r}); refusing to overwrite an input")
    if os.path.exists(out) and not os.stat(out).st_mode & 0o222 and not force:
        raise ValueError(f"{flag} {given!r} exists and is read-only; pass --force to replace it")
    _check_writable_folder(_existing_ancestor(os.path.dirname(out)), flag, given)
    return out


def check_output_folder(path, flag: str) -> str:
    """Refuse an output folder that is a file, lies under a file, or cannot be written; return it absolute."""
    given = os.fspath(path)
    out = os.path.abspath(given)
    if os.path.exists(out) and not os.path.isdir(out):
        raise ValueError(f"{flag} {given!r} is a file; give a folder")
    _check_writable_folder(_existing_ancestor(out), flag, given)
    return out


def check_not_overlapping(out, out_flag: str, source, source_flag: str) -> None:
    """Refuse an output folder that is, contains or lies inside a source folder (its files would be
    overwritten, or written among the originals and read back as sources next time)."""
    out_real, source_real = os.path.realpath(os.fspath(out)), os.path.realpath(os.fspath(source))
    if out_real == source_real:
        raise ValueError(f"{out_flag} {os.fspath(out)!r} is {source_flag} {os.fspath(source)!r}: its notebooks "
                         f"would be overwritten; give another folder")
    common = os.path.commonpath([out_real, source_real])
    if common == source_real:
        raise ValueError(f"{out_flag} {os.fspath(out)!r} lies inside {source_flag} {os.fspath(source)!r}; "
                         f"give a folder outside it")
    if common == out_real:
        raise ValueError(f"{out_flag} {os.fspath(out)!r} contains {source_flag} {os.fspath(source)!r}; "
                         f"give a folder outside it")


def lock_path(target) -> str:
    """The lock file of an output file or folder: ``<dir>/.<name>.ddp-lite.lock``, beside it (the same
    whether a folder exists yet or not)."""
    target = os.path.abspath(os.fspath(target)).rstrip(os.sep) or os.sep
    return os.path.join(os.path.dirname(target), f".{os.path.basename(target)}{LOCK_NAME}")


def _holder(path: str) -> dict | None:
    """Who holds the lock at ``path``: its JSON, or None when it is stale (its process is gone, or it was
    left unwritten for a minute)."""
    try:
        with open(path, encoding="utf-8") as handle:
            holder = json.load(handle)
        pid = int(holder["pid"])
    except FileNotFoundError:
        return None
    except (OSError, ValueError, KeyError, TypeError):
        try:  # being written this instant, or left half-written by a process killed then
            return None if time.time() - os.stat(path).st_mtime > 60 else {"pid": "?", "host": "?", "started": "?"}
        except OSError:
            return None
    if holder.get("host") == socket.gethostname():
        try:
            os.kill(pid, 0)
        except ProcessLookupError:
            return None
        except PermissionError:
            pass  # alive, another user's
    return holder


def _take(path: str, flag: str, given) -> None:
    record = json.dumps({"pid": os.getpid(), "host": socket.gethostname(),
                         "started": time.strftime("%Y-%m-%d %H:%M:%S")}).encode()
    for _ in range(2):
        try:
            fd = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o644)
        except FileExistsError:
            holder = _holder(path)
            if holder is not None:
                raise ValueError(f"{flag} {given!r}: another ddp-lite command (process {holder.get('pid')} on "
                                 f"{holder.get('host')}, since {holder.get('started')}) is writing it; wait for it "
                                 f"to finish (if no such command runs, delete {path})") from None
            with contextlib.suppress(FileNotFoundError):
                os.remove(path)  # stale: its process is gone
            continue
        try:
            os.write(fd, record)
        finally:
            os.close(fd)
        return
    raise ValueError(f"{flag} {given!r}: could not take the lock {path} (another command took it first)")


@contextlib.contextmanager
def _sigterm_raises():
    """Inside the block, SIGTERM raises KeyboardInterrupt (so cleanup runs) instead of ending the process
    on the spot; only in the main thread, and only where SIGTERM has its default action."""
    if threading.current_thread() is not threading.main_thread() or signal.getsignal(signal.SIGTERM) != signal.SIG_DFL:
        yield
        return

    def interrupt(signum, frame):
        raise KeyboardInterrupt("SIGTERM")
    signal.signal(signal.SIGTERM, interrupt)
    try:
        yield
    finally:
        signal.signal(signal.SIGTERM, signal.SIG_DFL)


@contextlib.contextmanager
def output_lock(targets, flag: str):
    """Hold the lock file of every path in ``targets`` (files or folders; :func:`lock_path`)
    for the block; ``ValueError`` naming ``flag`` when another live command holds one. SIGTERM inside
    the block raises ``KeyboardInterrupt``; the locks go at the end, whatever happened. Every output
    folder among ``targets`` is guarded for the block (``files.writing_inside``): a write through a
    symbolic link inside it is refused."""
    taken = []
    folders = [os.path.abspath(os.fspath(t)) for t in targets]  # a file target guards nothing below it
    with _sigterm_raises(), writing_inside(*folders):  # no writer writes through a link inside an output folder
        try:
            for target in dict.fromkeys(os.path.abspath(os.fspath(t)) for t in targets):
                path = lock_path(target)
                os.makedirs(os.path.dirname(path), exist_ok=True)
                _take(path, flag, target)
                taken.append(path)
            yield
        finally:
            for path in taken:
                with contextlib.suppress(OSError):
                    os.remove(path)


@contextlib.contextmanager
def _signals_held():
    """SIGTERM and SIGINT wait until the end of the block (main thread, POSIX)."""
    if not hasattr(signal, "pthread_sigmask") or threading.current_thread() is not threading.main_thread():
        yield
        return
    held = {signal.SIGTERM, signal.SIGINT}
    previous = signal.pthread_sigmask(signal.SIG_BLOCK, held)
    try:
        yield
    finally:
        signal.pthread_sigmask(signal.SIG_SETMASK, previous)


@contextlib.contextmanager
def output_set(targets, flag: str, overwrite_readonly: bool = False):
    """Write several output files as one: yields ``staged(target) -> temporary path`` to write each file
    of ``targets`` to; at the end of the block all are renamed over their targets together (signals held
    back), or, on any error, all are removed and every target is left as it was. Under
    :func:`output_lock` for the block's whole length (take it before the work: a concurrent command is
    refused at once, not after the work).

    Example:
        >>> import tempfile, os
        >>> out = os.path.join(tempfile.mkdtemp(), "depth.npy")
        >>> with output_set([out, out + ".txt"], "--out") as staged:
        ...     with open(staged(out), "wb") as depth, open(staged(out + ".txt"), "w") as note:
        ...         _ = depth.write(b"depth"), note.write("its note")
        >>> sorted(os.listdir(os.path.dirname(out)))
        ['depth.npy', 'depth.npy.txt']
    """
    targets = [os.path.abspath(os.fspath(t)) for t in targets]
    with output_lock(targets, flag):
        stack = contextlib.ExitStack()
        staged: dict = {}

        def stage(target) -> str:
            target = os.path.abspath(os.fspath(target))
            if target not in targets:
                raise ValueError(f"{target} is not one of this output set's files {targets}")
            if target not in staged:
                staged[target] = stack.enter_context(atomic_path(target, overwrite_readonly=overwrite_readonly))
            return staged[target]

        try:
            yield stage
        except BaseException as error:
            stack.__exit__(type(error), error, error.__traceback__)  # each temporary file removed
            raise
        with _signals_held():
            stack.close()  # each os.replace, in a row
