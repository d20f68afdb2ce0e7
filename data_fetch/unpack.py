"""Safe unpacking of .zip and .tar(.gz/.bz2/.xz) archives.

Every member is checked *before anything is written*: an absolute name (``/x``, ``C:x``, ``\\x``),
a ``..`` component, a backslash, a symbolic or hard link, or a device/FIFO member refuses the
whole archive with ``UnsafeArchiveError``. The kit's datasets are plain files and folders, so a
link of any kind is refused rather than judged. Tar members are then extracted with Python's
``filter="data"`` (where available) as a second line of defence.
"""
from __future__ import annotations

import os
import re
import stat
import tarfile
import zipfile
from pathlib import Path, PurePosixPath

from .download import FetchError

__all__ = ["UnsafeArchiveError", "safe_extract", "check_member_name"]


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


def safe_extract(archive, target) -> Path:
    """Unpack ``archive`` (.zip or .tar*) into the folder ``target`` after checking every member;
    returns ``target``. Refuses the whole archive (writing nothing) if any member is unsafe."""
    archive, target = Path(archive), Path(target)
    if zipfile.is_zipfile(archive):
        with zipfile.ZipFile(archive) as zf:
            members = zf.infolist()
            for info in members:
                check_member_name(info.filename, archive.name)
                if stat.S_ISLNK(info.external_attr >> 16):
                    raise UnsafeArchiveError(f"{archive.name}: member {info.filename!r} is a symbolic link")
                if not _inside(target, info.filename):
                    raise UnsafeArchiveError(f"{archive.name}: member {info.filename!r} resolves outside {target}")
            target.mkdir(parents=True, exist_ok=True)
            for info in members:
                zf.extract(info, target)
        return target
    if tarfile.is_tarfile(archive):
        with tarfile.open(archive, "r:*") as tf:
            members = tf.getmembers()
            for member in members:
                check_member_name(member.name, archive.name)
                if not (member.isfile() or member.isdir()):
                    kind = "link" if (member.issym() or member.islnk()) else "special file"
                    raise UnsafeArchiveError(f"{archive.name}: member {member.name!r} is a {kind}")
                if not _inside(target, member.name):
                    raise UnsafeArchiveError(f"{archive.name}: member {member.name!r} resolves outside {target}")
            target.mkdir(parents=True, exist_ok=True)
            if hasattr(tarfile, "data_filter"):  # Python >= 3.11.4 / 3.12
                tf.extractall(target, members=members, filter="data")
            else:
                tf.extractall(target, members=members)
        return target
    raise UnsafeArchiveError(f"{archive.name} is neither a zip nor a tar archive")
