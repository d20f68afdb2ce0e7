"""Install a dataset's files from a local folder instead of the network (``fetch NAME --from DIR``).

``DIR`` may be laid out in either of two ways (both are looked at, file by file):

* the dataset's own names, as ``fetch`` would leave them: ``HalfSize/Plastic/view1.png``,
  ``MiddEval3/trainingQ/Piano/im0.png`` (or ``trainingQ/Piano/im0.png``), ``plastic-disp-hole.png``;
* the layout of the offline Middlebury copies: ``2006-Plastic/view1.png`` and ``2005-Art/...``
  (HalfSize files of ``middlebury2006`` / ``middlebury2005``), ``2014-Piano-Q/im0.png`` (the files
  ``middlebury2014q``'s archives unpack to), ``depthcomp/plastic-disp-hole.png``.

Every file is copied to a temporary name inside the dataset folder, verified there (decoded-pixel
hash, else pinned byte SHA-256, else the hash recorded in ``registry.json``), and renamed to its
final name only once *every* selected file passed: one mismatch installs nothing. ``DIR`` is only
read. A file with no pin and no record is refused unless ``trust_first_download``; it is then
recorded in ``registry.json`` as ``fetch`` records a first download.
"""
from __future__ import annotations

import os
import re
import shutil
import tempfile
from dataclasses import dataclass
from pathlib import Path

import pooch

from .download import ChecksumError, FetchError, content_problem, entry_path
from .fetch import (REGISTRY_FILE, UnpinnedFileError, _check_writable, _read_records, _record_many, data_dir,
                    trusted_message)
from .install_lock import TEMP_PREFIX, check_say, install_lock, remove_spent_parts, remove_stale_temporaries
from .pixels import pixel_sha256, text_sha256
from .registry import Dataset, get_dataset
from .select import select_names

__all__ = ["install_from", "LocalInstall", "shared_to_registry", "source_names", "installable"]

_SHARED = (  # offline-copy layout -> (dataset, name inside the dataset folder)
    (re.compile(r"(2005|2006)-([^/]+)/([^/]+)"), lambda m: (f"middlebury{m[1]}", f"HalfSize/{m[2]}/{m[3]}")),
    (re.compile(r"2014-([^/]+)-Q/([^/]+)"), lambda m: ("middlebury2014q", f"MiddEval3/trainingQ/{m[1]}/{m[2]}")),
    (re.compile(r"depthcomp/([^/]+)"), lambda m: ("depthcomp", m[1])),
)


def shared_to_registry(relpath: str) -> tuple[str, str] | None:
    """``'2006-Plastic/view1.png'`` → ``('middlebury2006', 'HalfSize/Plastic/view1.png')``; None if no rule fits."""
    for pattern, convert in _SHARED:
        match = pattern.fullmatch(relpath)
        if match:
            return convert(match)
    return None


def source_names(dataset_name: str, name: str) -> list[str]:
    """Where, relative to ``DIR``, the file ``name`` of ``dataset_name`` may be: its own name first."""
    names = [name]
    match = re.fullmatch(r"HalfSize/([^/]+)/([^/]+)", name)
    if match and dataset_name in ("middlebury2005", "middlebury2006"):
        names.append(f"{dataset_name[-4:]}-{match[1]}/{match[2]}")
    match = re.fullmatch(r"MiddEval3/(trainingQ/([^/]+)/([^/]+))", name)
    if match and dataset_name == "middlebury2014q":
        names += [match[1], f"2014-{match[2]}-Q/{match[3]}"]
    if dataset_name == "depthcomp" and "/" not in name:
        names.append(f"depthcomp/{name}")
    return names


def installable(dataset: Dataset) -> list[tuple[str, str | None, str | None]]:
    """``(name, pixel_sha256, sha256)`` of every file ``--from`` can install: each plain file, and for an
    archive with pinned members those members (the archive itself otherwise)."""
    out = []
    for entry in dataset.files:
        if entry.members:
            out += [(member, pin, None) for member, pin in entry.members]
        else:
            out.append((entry.name, entry.pixel_sha256, entry.sha256))
    return out


@dataclass(frozen=True)
class LocalInstall:
    """What ``install_from`` did: ``installed`` (paths copied now), ``present`` (already there and
    verified), ``missing`` (names of the selected files that ``DIR`` did not have)."""

    installed: tuple[Path, ...]
    present: tuple[Path, ...]
    missing: tuple[str, ...]


def _find(source: Path, dataset_name: str, name: str) -> Path | None:
    for candidate in source_names(dataset_name, name):
        path = source / candidate
        if path.is_file():
            return path
    return None


def _check(path: Path, name: str, origin, pixel: str | None, byte: str | None, text: str | None = None) -> None:
    """ChecksumError unless ``path`` matches ``pixel`` (decoded content) or ``byte`` (SHA-256 of its bytes; for a
    text file, or of its normalised text, or that matches ``text``, the recorded hash of the normalised text)."""
    if pixel:
        try:
            actual = pixel_sha256(path)
        except ValueError as error:
            raise ChecksumError(f"{name} (from {origin}) cannot be decoded, so its pixel hash cannot be checked: "
                                f"{error}") from None
        if actual != pixel:
            raise ChecksumError(f"{name} (from {origin}): decoded-pixel SHA-256 is {actual}, the registry pins "
                                f"{pixel}; refused, nothing was installed")
    elif byte:
        actual = pooch.file_hash(str(path))
        # a text file is compared as text too: the same text saved with a byte-order mark or CRLF line ends
        as_text = text_sha256(path)  # None for a file that is not text
        if actual != byte.split(":")[-1] and (as_text is None or as_text not in (byte.split(":")[-1], text)):
            raise ChecksumError(f"{name} (from {origin}): SHA-256 is {actual}, expected {byte}; refused, nothing "
                                f"was installed")


def install_from(dataset, source, dest=None, only=None, trust_first_download: bool = False,
                 say=print) -> LocalInstall:
    """Copy ``dataset``'s files found in the folder ``source`` into ``<root>/<dataset>/``, verified first."""
    if isinstance(dataset, str):
        dataset = get_dataset(dataset)
    if not isinstance(dataset, Dataset):
        raise TypeError(f"dataset must be a name or a Dataset, got {type(dataset).__name__}")
    say = check_say(say)  # before any work: a bad one found after the copies would leave an install half done
    if not isinstance(trust_first_download, bool):
        raise TypeError(f"trust_first_download must be True or False, got {type(trust_first_download).__name__} "
                        f"{trust_first_download!r}")
    if source is None or not str(source).strip():
        raise ValueError("source must name a folder (--from DIR), got nothing")
    source = Path(source).expanduser()
    if not source.exists():
        raise ValueError(f"source: {source} does not exist (--from must name a folder holding the files)")
    if not source.is_dir():
        raise ValueError(f"source: {source} is not a folder (--from must name a folder holding the files)")
    root = data_dir(dest)
    folder = entry_path(root, dataset.name, f"dataset {dataset.name!r}")
    for where in (root, folder):
        if where.exists() and not where.is_dir():
            raise FetchError(f"dest: {where} is a file; the data root and its dataset folders must be folders")
    if folder.resolve() == source.resolve() or source.resolve() in folder.resolve().parents:
        raise ValueError(f"source: {source} holds the dataset folder {folder}; copy from a folder outside it")
    targets = installable(dataset)
    if only:
        patterns = [only] if isinstance(only, str) else list(only)
        chosen = set(select_names([t[0] for t in targets], patterns))
        targets = [t for t in targets if t[0] in chosen]
        if not targets:
            raise ValueError(f"only={patterns!r} matches none of the {dataset.name} files --from can install "
                             f"(python -m data_fetch list {dataset.name} lists them; --only takes a scene, a folder "
                             f"or a glob)")
    for name, _, _ in targets:  # the one guard: every name stays inside the dataset folder
        entry_path(folder, name, f"{dataset.name} entry {name!r}")
    _check_writable(folder)
    with install_lock(root, dataset.name, say):  # one install of this folder at a time: no record is lost
        remove_stale_temporaries(root, folder, [f.name for f in dataset.files], say)
        result = _install(dataset, source, folder, targets, trust_first_download, say)
        remove_spent_parts(result.installed + result.present)
    return result


def _install(dataset: Dataset, source: Path, folder: Path, targets, trust_first_download: bool, say) -> LocalInstall:
    """``install_from``'s work, under the install lock: every target found in ``source`` staged, verified and
    installed (or nothing, on one failure); trusted ones recorded."""
    records = _read_records(folder) if folder.is_dir() else {}
    found, missing, present = [], [], []
    for name, pixel, byte in targets:
        origin = _find(source, dataset.name, name)
        if origin is None:
            missing.append(name)
            continue
        recorded = records.get(name, {}).get("sha256")
        final = folder / name
        if os.path.lexists(final):  # already installed: verified, never overwritten
            if not final.is_file():
                raise FetchError(f"{final} is in the way and is not a file; move it away and run again")
            if pixel or byte or recorded:
                _check(final, name, final, pixel, byte or recorded, records.get(name, {}).get("text_sha256"))
                present.append(final)
                continue
            raise UnpinnedFileError(f"{final} is already there with no pinned or recorded hash, so it cannot be "
                                    f"verified; move it away (or delete it) and run again")
        found.append((name, origin, pixel, byte or recorded))
    unpinned = [name for name, _, pixel, byte in found if not (pixel or byte)]
    if unpinned and not trust_first_download:
        raise UnpinnedFileError(
            f"{len(unpinned)} file(s) have no pinned hash (pixel or byte) and none is recorded in "
            f"{folder / REGISTRY_FILE}: {', '.join(unpinned[:5])}{' ...' if len(unpinned) > 5 else ''}.\n"
            f"Re-run with --trust-first-download to accept them as they are in {source}, record their SHA-256 "
            f"there, and verify every later fetch against it.")
    staged: list[tuple[Path, Path]] = []
    trusted: list = []
    try:
        for name, origin, pixel, byte in found:
            final = folder / name
            final.parent.mkdir(parents=True, exist_ok=True)
            handle, temporary = tempfile.mkstemp(prefix=f"{TEMP_PREFIX}{final.name}.", suffix=final.suffix,
                                                 dir=final.parent)
            os.close(handle)
            staged.append((Path(temporary), final))
            shutil.copyfile(origin, temporary)  # a copy: the source is never touched
            _check(Path(temporary), name, origin, pixel, byte, records.get(name, {}).get("text_sha256"))
            problem = None if (pixel or byte) else content_problem(temporary, name)  # before it is trusted
            if problem:
                raise FetchError(f"{problem} (from {origin}); --trust-first-download records only a file that is "
                                 f"what its name says; nothing was installed")
        # the records first, in one write: an install killed before its renames leaves records of files
        # not yet there (the next one checks its copies against them), never files with no record
        trusted = [(_Named(name), pooch.file_hash(str(temporary)), "trust-first-download",
                    f"copied from {origin} by fetch --from", text_sha256(temporary))
                   for (name, origin, pixel, byte), (temporary, _) in zip(found, staged) if not (pixel or byte)]
        if trusted:
            _record_many(folder, trusted)
        for temporary, final in staged:
            os.replace(temporary, final)
    finally:
        for temporary, _ in staged:
            Path(temporary).unlink(missing_ok=True)
    for entry, digest, *_ in trusted:
        say(trusted_message(entry.name, digest, folder))
    result = LocalInstall(tuple(folder / name for name, *_ in found), tuple(present), tuple(missing))
    verified = sum(1 for _, _, pixel, byte in found if pixel or byte)
    say(f"{dataset.name}: installed {len(result.installed)} file(s) into {folder} ({verified} verified against a "
        f"pinned or recorded hash, {len(result.installed) - verified} trusted on first use); "
        f"{len(present)} already there and verified; {source} did not have {len(missing)} of the "
        f"{len(targets)} selected file(s)"
        + (f" (e.g. {', '.join(missing[:3])})" if missing else ""))
    return result


@dataclass(frozen=True)
class _Named:
    """What ``_record`` reads from an entry: its name and URL (none: copied from a folder)."""

    name: str
    url: str | None = None
