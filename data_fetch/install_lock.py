"""One install at a time per dataset folder, and what a killed install left behind swept up.

``fetch`` and ``fetch --from`` read ``registry.json``, add a record and write it back; two of them at
once in one dataset folder would each write back what it read, and one's records would be lost (files
installed with no hash to verify them by). So each holds :func:`install_lock` for its whole run: a lock
file beside the dataset folder, ``<root>/.<dataset>.ddp-fetch.lock``, locked with ``flock`` (released by
the kernel when its process ends, however it ends: a killed install never leaves a lock that blocks the
next). A second install waits for the first, saying so, then finds its files there and verifies them.

Every temporary file an install makes starts with :data:`TEMP_PREFIX` (staged copies, ``registry.json``
and unpack markers on their way in) or is pooch's ``tmpXXXXXXXX`` beside a download, or the unpack
folder ``<root>/.<dataset>.unpack-*``. Holding the lock means no other install of the dataset is running,
so any such file found then was left by one that was killed: :func:`remove_stale_temporaries` removes
them (and names them) before the new install starts. An interrupted download's ``<file>.part`` is not a
temporary: the next ``fetch`` resumes from it (``download.py``), and it goes once its file is installed
(:func:`remove_spent_parts`).

POSIX (``fcntl.flock``); where that does not exist (Windows), ``msvcrt.locking`` on the lock file.
"""
from __future__ import annotations

import contextlib
import os
import re
import shutil
from pathlib import Path

__all__ = ["TEMP_PREFIX", "install_lock", "remove_stale_temporaries", "remove_spent_parts", "check_say"]

TEMP_PREFIX = ".ddp-fetch-tmp-"
_POOCH_TEMPORARY = re.compile(r"tmp[a-z0-9_]{8}")  # tempfile.NamedTemporaryFile(dir=...), pooch's download file
_OLD_TEMPORARIES = (re.compile(r"\.tmp-[a-z0-9_]{8}\.(json|unpacked)"),  # written before TEMP_PREFIX existed
                    re.compile(r"\..+\.[a-z0-9_]{8}\.from(\.[^./]*)?"))


def check_say(say):
    """``say`` as a function of one message: None → say nothing; anything else not callable → TypeError, before
    any work (a bad ``say`` found after the copies would leave an install half done)."""
    if say is None:
        return lambda message: None
    if not callable(say):
        raise TypeError(f"say must be a function taking one message (print, a list's append) or None for silence, "
                        f"got {type(say).__name__} {say!r}")
    return say


def lock_file(root: Path, dataset: str) -> Path:
    """The lock file of ``<root>/<dataset>``: beside it, so the dataset folder holds only the data."""
    return Path(root) / f".{dataset}.ddp-fetch.lock"


def _lock(fd: int, blocking: bool) -> bool:
    try:
        import fcntl
    except ImportError:  # Windows
        import msvcrt
        while True:
            try:
                msvcrt.locking(fd, msvcrt.LK_NBLCK, 1)
                return True
            except OSError:
                if not blocking:
                    return False
                import time
                time.sleep(0.1)
    try:
        fcntl.flock(fd, fcntl.LOCK_EX | (0 if blocking else fcntl.LOCK_NB))
    except BlockingIOError:
        return False
    return True


def _holder(path: Path) -> str:
    try:
        return f"process {path.read_text(encoding='ascii').strip() or '?'}"
    except (OSError, UnicodeDecodeError):
        return "another process"


@contextlib.contextmanager
def install_lock(root, dataset: str, say):
    """Hold the install lock of ``<root>/<dataset>`` for the block (waiting, with a word, while another
    install holds it); ``root`` is created if missing. The lock file is removed at the end."""
    root = Path(root)
    root.mkdir(parents=True, exist_ok=True)
    path = lock_file(root, dataset)
    waited = False
    while True:
        fd = os.open(path, os.O_RDWR | os.O_CREAT, 0o644)
        try:
            if not _lock(fd, blocking=False):
                if not waited:
                    say(f"another install into {root / dataset} is running ({_holder(path)}); waiting for it "
                        f"to finish")
                    waited = True
                _lock(fd, blocking=True)
            try:  # the holder before us removes the file as it lets go: a lock on that file guards nothing
                same = os.path.samestat(os.fstat(fd), os.stat(path))
            except FileNotFoundError:
                same = False
        except BaseException:
            os.close(fd)
            raise
        if same:
            break
        os.close(fd)
    try:
        os.ftruncate(fd, 0)
        os.write(fd, str(os.getpid()).encode("ascii"))
        yield
    finally:
        with contextlib.suppress(OSError):
            os.unlink(path)  # while still held: a waiter that then gets it sees the file gone and starts again
        os.close(fd)


def remove_stale_temporaries(root, folder, download_names=(), say=print) -> list[Path]:
    """Remove what an install of ``folder`` (a dataset folder under ``root``) that was killed left behind;
    call it holding :func:`install_lock`. ``download_names``: the dataset's file names, beside which pooch
    keeps its temporary download. Returns the paths removed; ``say`` names them."""
    root, folder = Path(root), Path(folder)
    stale: list[Path] = []
    if folder.is_dir():
        for where, folders, files in os.walk(folder):
            for name in folders + files:
                if name.startswith(TEMP_PREFIX) or any(p.fullmatch(name) for p in _OLD_TEMPORARIES):
                    stale.append(Path(where) / name)
            folders[:] = [f for f in folders if not f.startswith(TEMP_PREFIX)]
        beside = {(folder / name).parent for name in download_names}
        for where in sorted(beside):
            if where.is_dir():
                stale += [p for p in where.iterdir() if _POOCH_TEMPORARY.fullmatch(p.name) and p.is_file()
                          and not p.is_symlink()]
    if root.is_dir():
        stale += [p for p in root.iterdir() if p.name.startswith((f".{folder.name}.unpack-",
                                                                  f"{TEMP_PREFIX}{folder.name}.unpack-"))]
    for path in stale:
        if path.is_dir() and not path.is_symlink():
            shutil.rmtree(path, ignore_errors=True)
        else:
            with contextlib.suppress(FileNotFoundError):
                path.unlink()
    if stale:
        shown = ", ".join(str(p.relative_to(root)) for p in stale[:5]) + (" ..." if len(stale) > 5 else "")
        say(f"removed {len(stale)} temporary file(s) an interrupted install left in {root}: {shown}")
    return stale


def remove_spent_parts(paths) -> None:
    """Remove the ``<file>.part`` (and its ``.part.json``) of each installed ``paths``: an interrupted download of
    a file that is now installed and verified (by this fetch, or copied by ``--from``) will never be resumed."""
    for path in paths:
        path = Path(path)
        for spent in (path.with_name(path.name + ".part"), path.with_name(path.name + ".part.json")):
            if spent.is_file() and not spent.is_symlink():
                spent.unlink()
