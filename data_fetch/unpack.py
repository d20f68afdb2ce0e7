"""Safe unpacking of .zip and .tar(.gz/.bz2/.xz) archives.

Every member is checked *before anything is written*: an absolute name (``/x``, ``C:x``, ``\\x``),
a ``..`` component, a backslash, a symbolic or hard link, or a device/FIFO member refuses the
whole archive with ``UnsafeArchiveError``. The kit's datasets are plain files and folders, so a
link of any kind is refused rather than judged. Tar members are then extracted with Python's
``filter="data"`` (where available) as a second line of defence.

An archive may not expand to more than ``max_ratio`` times its own size, nor to more than the
free disk space (both from the sizes its members declare; zip reading stops at the declared size).
Everything is extracted into a temporary folder beside the target and moved into place only
after every member was read back whole (zip CRCs, tar/gzip lengths): a corrupt or truncated
archive is a ``FetchError`` and leaves the target as it was.
"""
from __future__ import annotations

import collections
import os
import re
import shutil
import stat
import tarfile
import tempfile
import zipfile
import zlib
from pathlib import Path, PurePosixPath

from .download import FetchError

__all__ = ["UnsafeArchiveError", "safe_extract", "check_member_name", "MAX_RATIO"]

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


def safe_extract(archive, target, max_ratio: float = MAX_RATIO) -> Path:
    """Unpack ``archive`` (.zip or .tar*) into the folder ``target`` after checking every member;
    returns ``target``. Refuses the whole archive (writing nothing) if any member is unsafe, if it
    would expand to more than ``max_ratio`` × its size or the free space, or if it is corrupt."""
    archive, target = Path(archive), Path(target)
    if zipfile.is_zipfile(archive):
        handle = zipfile.ZipFile(archive)
        members = handle.infolist()
        for info in members:
            check_member_name(info.filename, archive.name)
            if stat.S_ISLNK(info.external_attr >> 16):
                raise UnsafeArchiveError(f"{archive.name}: member {info.filename!r} is a symbolic link")
        total = sum(info.file_size for info in members)
        names = [info.filename for info in members]
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
        names = [member.name for member in members]
    with handle:
        duplicates = sorted(n for n, k in collections.Counter(names).items() if k > 1 and not n.endswith("/"))
        if duplicates:  # the second copy would silently replace the first
            raise UnsafeArchiveError(f"{archive.name}: member(s) {duplicates[:3]} appear more than once")
        for name in names:
            if not _inside(target, name):
                raise UnsafeArchiveError(f"{archive.name}: member {name!r} resolves outside {target}")
        target.mkdir(parents=True, exist_ok=True)
        _check_expansion(archive, target, total, max_ratio)
        staging = Path(tempfile.mkdtemp(dir=target.parent, prefix=f".{target.name}.unpack-"))
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
