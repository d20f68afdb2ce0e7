"""Output paths (of the command line and the classroom kit), checked before any work starts.

A command that renders for minutes and then finds it cannot write its result has wasted those
minutes; one that writes its output over its own input has lost the input. Every ``--out``-like
flag goes through one of these checks first; each raises ``ValueError`` naming the flag.
"""
from __future__ import annotations

import os
import tempfile

__all__ = ["check_output_file", "check_output_folder", "check_not_overlapping"]


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
    if os.path.isdir(out):
        raise ValueError(f"{flag} {given!r} is a folder; give a file name such as {example}")
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
