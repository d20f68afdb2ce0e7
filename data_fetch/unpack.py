"""Safe unpacking of .zip and .tar(.gz/.bz2/.xz) archives.

Every member is checked *before anything is written*: an absolute name (``/x``, ``C:x``, ``\\x``),
a ``..`` component, a backslash, a symbolic or hard link, or a device/FIFO member refuses the
whole archive with ``UnsafeArchiveError``. The kit's datasets are plain files and folders, so a
link of any kind is refused rather than judged. Tar members are then extracted with Python's
``filter="data"`` (where available) as a second line of defence.

An archive may not expand to more than ``max_ratio`` times its own size, nor to more than the
free disk space (both from the sizes its members declare; zip reading stops at the declared size).
Member names are compared as the file system will see them: ``./a.txt``, ``a.txt`` and ``dir//a.txt``
vs ``dir/a.txt`` are the same file, and so are names that differ only in case or Unicode form (one
file on macOS and Windows). Two members naming one file, or a file that another member puts files
under, refuse the whole archive: one would silently replace the other.

Everything is extracted into a temporary folder beside the target and moved into place only
after every member was read back whole (zip CRCs, tar/gzip lengths): a corrupt or truncated
archive is a ``FetchError`` and leaves the target as it was.
"""
from __future__ import annotations

import os
import re
import shutil
import stat
import tarfile
import tempfile
import unicodedata
import zipfile
import zlib
from pathlib import Path, PurePosixPath

from .download import FetchError
from .install_lock import TEMP_PREFIX

__all__ = ["UnsafeArchiveError", "safe_extract", "check_member_name", "archive_files", "member_path", "MAX_RATIO"]

MAX_RATIO = 200  # unpacked bytes per archive byte; PNG/PFM datasets stay far below, a zip bomb does not
_TAR_SUFFIXES = (".tar", ".tar.gz", ".tgz", ".tar.bz2", ".tbz2", ".tar.xz", ".txz")


class UnsafeArchiveError(FetchError):
    """An archive member would land outside the target folder (or is a link or special file)."""


def check_member_name(name: str, archive="archive") -> None:
    """Raise ``UnsafeArchiveError`` unless ``name`` is a plain relative path with no ``..``."""
    if not name or "\x00" in name or "\\" in name:
        raise UnsafeArchiveError(f"{archive}: member {name!r} has an empty name, a NUL or a backslash")
    if name.startswith("/") or re.match(r"^[A-Za-z]:", name):
        raise UnsafeArchiveError(f"{archive}: member {name!r} is an absolute path")
    if ".." in PurePosixPath(name).parts:
        raise UnsafeArchiveError(f"{archive}: member {name!r} contains '..'")


def member_path(name: str) -> str:
    """A member's name as the path it lands on: '.' and empty components dropped (``./a//b/`` → ``a/b``)."""
    return "/".join(part for part in name.split("/") if part not in ("", "."))


def _same_file_key(path: str) -> str:
    """Names that one file system or another takes for the same file: any case, any Unicode form."""
    return unicodedata.normalize("NFC", path).casefold()


def _check_one_member_per_file(names_and_kinds, archive: str) -> None:
    """Refuse two members landing on one file, and a file that another member treats as a folder."""
    files, folders = {}, {}
    for name, is_dir in names_and_kinds:
        path = member_path(name)
        if not path:
            if is_dir:
                continue  # the archive's own root folder ("./")
            raise UnsafeArchiveError(f"{archive}: member {name!r} names no file")
        key = _same_file_key(path)
        if is_dir:
            if key in files:
                raise UnsafeArchiveError(f"{archive}: members {files[key]!r} and {name!r} are a file and a folder "
                                         f"of the same name")
            folders.setdefault(key, name)
            continue
        if key in files or key in folders:
            other = files.get(key, folders.get(key))
            if other == name:
                raise UnsafeArchiveError(f"{archive}: member {name!r} appears more than once; the same file twice, "
                                         f"one would replace the other")
            raise UnsafeArchiveError(f"{archive}: members {other!r} and {name!r} land on the same file (they differ "
                                     f"only in spelling: './', '//', case or Unicode form); one would replace the other")
        files[key] = name
    for key, name in list(files.items()) + list(folders.items()):
        parts = key.split("/")
        for depth in range(1, len(parts)):
            parent = "/".join(parts[:depth])
            if parent in files:
                raise UnsafeArchiveError(f"{archive}: member {name!r} lies under {files[parent]!r}, which is a file")


def archive_files(archive) -> dict:
    """``{path: size}`` of the regular files an archive unpacks (paths as :func:`member_path` gives them)."""
    archive = Path(archive)
    if zipfile.is_zipfile(archive):
        with zipfile.ZipFile(archive) as handle:
            return {member_path(i.filename): i.file_size for i in handle.infolist() if not i.is_dir()}
    with _open_tar(archive) as handle:
        return {member_path(m.name): m.size for m in handle.getmembers() if m.isfile()}


def _inside(target: Path, name: str) -> bool:
    real_target = os.path.realpath(target)
    real = os.path.realpath(os.path.join(real_target, name))
    return os.path.commonpath([real_target, real]) == real_target


def _check_expansion(archive: Path, target: Path, total: int, max_ratio: float) -> None:
    size = archive.stat().st_size
    if total > max_ratio * max(size, 1):
        raise UnsafeArchiveError(f"{archive.name}: would expand to {total:,} bytes, more than {max_ratio:g} × its "
                                 f"size ({size:,} bytes); refusing a possible zip bomb (safe_extract's max_ratio)")
    free = shutil.disk_usage(target).free
    if total > free:
        raise FetchError(f"{archive.name}: would expand to {total:,} bytes but {target} has {free:,} bytes free")


def _move_into(source: Path, target: Path) -> None:
    """Move every file under ``source`` to the same relative place under ``target`` (same file system)."""
    for folder, _, files in os.walk(source):
        destination = target / Path(folder).relative_to(source)
        destination.mkdir(parents=True, exist_ok=True)
        for name in files:
            os.replace(Path(folder) / name, destination / name)


def _open_tar(archive: Path):
    try:
        return tarfile.open(archive, "r:*")
    except (tarfile.TarError, EOFError, OSError, zlib.error) as error:
        if archive.name.lower().endswith(_TAR_SUFFIXES):
            raise FetchError(f"{archive.name} is a corrupt or truncated tar archive ({error}); "
                             f"delete it and fetch again") from None
        raise UnsafeArchiveError(f"{archive.name} is neither a zip nor a tar archive") from None


def safe_extract(archive, target, max_ratio: float = MAX_RATIO, only=None) -> Path:
    """Unpack ``archive`` (.zip or .tar*) into the folder ``target`` after checking every member;
    returns ``target``. Refuses the whole archive (writing nothing) if any member is unsafe, if two
    land on one file, if it would expand to more than ``max_ratio`` × its size or the free space, or if
    it is corrupt. ``only``: the file paths (:func:`archive_files`' keys) to unpack; None: all."""
    archive, target = Path(archive), Path(target)
    if zipfile.is_zipfile(archive):
        handle = zipfile.ZipFile(archive)
        members = handle.infolist()
        for info in members:
            check_member_name(info.filename, archive.name)
            if stat.S_ISLNK(info.external_attr >> 16):
                raise UnsafeArchiveError(f"{archive.name}: member {info.filename!r} is a symbolic link")
        total = sum(info.file_size for info in members)
        names = [(info.filename, info.is_dir()) for info in members]
    else:
        handle = _open_tar(archive)
        try:
            members = handle.getmembers()
        except (tarfile.TarError, EOFError, OSError, zlib.error) as error:
            handle.close()
            raise FetchError(f"{archive.name} is a corrupt or truncated tar archive ({error}); "
                             f"delete it and fetch again") from None
        for member in members:
            check_member_name(member.name, archive.name)
            if not (member.isfile() or member.isdir()):
                kind = "link" if (member.issym() or member.islnk()) else "special file"
                raise UnsafeArchiveError(f"{archive.name}: member {member.name!r} is a {kind}")
        total = sum(member.size for member in members)
        names = [(member.name, member.isdir()) for member in members]
    with handle:
        _check_one_member_per_file(names, archive.name)
        if only is not None:
            only = set(only)
            members = [m for m, (name, is_dir) in zip(members, names) if not is_dir and member_path(name) in only]
            total = sum(m.file_size if isinstance(m, zipfile.ZipInfo) else m.size for m in members)
        for name, _ in names:
            if not _inside(target, name):
                raise UnsafeArchiveError(f"{archive.name}: member {name!r} resolves outside {target}")
        target.mkdir(parents=True, exist_ok=True)
        _check_expansion(archive, target, total, max_ratio)
        staging = Path(tempfile.mkdtemp(dir=target.parent, prefix=f"{TEMP_PREFIX}{target.name}.unpack-"))
        try:
            if isinstance(handle, zipfile.ZipFile):
                for info in members:
                    handle.extract(info, staging)  # reads each member whole: a bad CRC raises here
            elif hasattr(tarfile, "data_filter"):  # Python >= 3.11.4 / 3.12
                handle.extractall(staging, members=members, filter="data")
            else:
                handle.extractall(staging, members=members)
        except (zipfile.BadZipFile, tarfile.TarError, EOFError, zlib.error, OSError) as error:
            shutil.rmtree(staging, ignore_errors=True)
            raise FetchError(f"{archive.name} could not be unpacked ({error}): it is corrupt or truncated (or the "
                             f"disk is full). Nothing was unpacked.") from None
        except BaseException:
            shutil.rmtree(staging, ignore_errors=True)
            raise
        try:
            _move_into(staging, target)
        finally:
            shutil.rmtree(staging, ignore_errors=True)
    return target
