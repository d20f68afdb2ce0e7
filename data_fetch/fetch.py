"""``fetch``: download (or take the user's manual download), verify, record and unpack a dataset.

Layout under the data root (``--dest``, else ``$DDP_DATA``, else platformdirs'
``user_data_dir("ddp-lite")``)::

    <root>/<dataset>/<file>             the verified file (final name only after its hash matched)
    <root>/<dataset>/<file>.part        an interrupted download, resumed by the next fetch
    <root>/<dataset>/registry.json      hashes recorded by --trust-first-download (when, and whose bytes:
                                        downloaded by that fetch, or a manual download the user placed)
    <root>/<dataset>/.<file>.unpacked   marker: this archive (this hash) was unpacked here
"""
from __future__ import annotations

import datetime
import itertools
import json
import os
from pathlib import Path

import pooch

from ddp_lite.core.files import regular_file, write_bytes_atomic
from ddp_lite.data.installed import ENV_VAR, data_root
from .download import (ChecksumError, FetchError, ResumableDownloader, check_fetch_numbers, content_problem,
                       entry_path, normal_sha256)
from .install_lock import TEMP_PREFIX, check_say, install_lock, remove_spent_parts, remove_stale_temporaries
from .pixels import text_sha256
from .registry import Dataset, RemoteFile, get_dataset
from .select import select_names
from .unpack import archive_files, safe_extract

__all__ = ["fetch", "data_dir", "ManualDownloadRequired", "UnpinnedFileError", "ENV_VAR", "REGISTRY_FILE"]

REGISTRY_FILE = "registry.json"


class ManualDownloadRequired(FetchError):
    """The dataset sits behind a form; the message says what to download and where to put it."""


class UnpinnedFileError(FetchError):
    """A file has no pinned SHA-256 and ``trust_first_download`` was not given."""


def data_dir(dest=None) -> Path:
    """The data root: ``dest`` if given, else ``$DDP_DATA``, else ``user_data_dir('ddp-lite')``
    (``ddp_lite.data.installed.data_root``: the one rule every reader of the data follows too)."""
    return data_root(dest)


def _check_writable(folder: Path) -> None:
    """Refuse, before any download, a dataset folder (or its nearest existing parent) we cannot write to."""
    existing = folder
    while not existing.exists() and existing != existing.parent:
        existing = existing.parent
    if not os.access(existing, os.W_OK | os.X_OK):
        raise FetchError(f"dest: {existing} is not writable, so {folder} cannot hold the data; pick another data "
                         f"root (--dest, or ${ENV_VAR}) or make it writable")


def _read_records(folder: Path) -> dict:
    path = folder / REGISTRY_FILE
    if not path.exists():
        return {}
    try:
        records = json.loads(regular_file(path, "registry").read_text(encoding="utf-8"))  # not a FIFO: no wait
    except (json.JSONDecodeError, UnicodeDecodeError) as error:
        raise FetchError(f"{path} is not valid JSON ({error}); fix or delete it") from None
    if not isinstance(records, dict):
        raise FetchError(f"{path} must hold a JSON object {{file name: record}}, got {type(records).__name__}; "
                         f"fix or delete it")
    for name, record in records.items():
        digest = record.get("sha256") if isinstance(record, dict) else None
        try:
            record["sha256"] = normal_sha256(digest, "sha256")  # upper case or a prefix: the same hash
        except (ValueError, TypeError):
            digest = None
        if not isinstance(digest, str):
            raise FetchError(f"{path}: the entry for {name!r} must be a mapping with a 64-hex-digit 'sha256', "
                             f"got {record!r}; fix or delete it")
    return records


def _record(folder: Path, entry: RemoteFile, sha256: str, how: str, bytes_from: str) -> None:
    _record_many(folder, [(entry, sha256, how, bytes_from, text_sha256(folder / entry.name))])


def _record_many(folder: Path, records_to_add) -> None:
    """Add ``(entry, sha256, how, bytes_from, text_sha256)`` records to ``registry.json`` in one write (read,
    added to, written back atomically: the caller holds the install lock, so no other install writes between).
    ``text_sha256``: for a text file, the SHA-256 of its normalised text (``pixels.text_sha256``), else None."""
    records = _read_records(folder)
    now = datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds")
    for entry, sha256, how, bytes_from, text in records_to_add:
        records[entry.name] = {"sha256": sha256, "url": entry.url, "how": how, "bytes_from": bytes_from,
                               "recorded": now, **({"text_sha256": text} if text else {})}
    write_bytes_atomic(folder / REGISTRY_FILE, (json.dumps(records, indent=2, sort_keys=True) + "\n").encode(),
                       prefix=TEMP_PREFIX)


def trusted_message(name: str, digest: str, folder: Path) -> str:
    """What an install says of a file it took on trust: that nothing verified it, and what now will."""
    return (f"{name}: installed unverified (no pinned hash, byte or pixel, exists for it): trusted on first use, its "
            f"SHA-256 {digest} is recorded in {folder / REGISTRY_FILE} and verifies every later install")


def _known_hash(folder: Path, entry: RemoteFile, trust: bool) -> str | None:
    """The pinned hash, else the recorded one, else None (allowed only with ``trust``)."""
    known = entry.sha256 or _read_records(folder).get(entry.name, {}).get("sha256")
    if known is None and not trust and not entry.pixel_sha256:  # a pixel pin verifies it after the download
        raise UnpinnedFileError(
            f"{entry.name} has no pinned SHA-256 (the registry marks it unverified: nobody has checked its bytes "
            f"yet) and none is recorded in {folder / REGISTRY_FILE}.\nRe-run with --trust-first-download to accept "
            f"what arrives now, record its SHA-256 there, and verify every later fetch against it.")
    return known


def _check_pixels(path: Path, name: str, pinned: str) -> str | None:
    """None if the decoded content of ``path`` has the pinned pixel hash, else a sentence saying what differs."""
    from .pixels import pixel_sha256

    try:
        actual = pixel_sha256(path)
    except (ValueError, OSError) as error:
        return f"{name} cannot be decoded ({error}), so its pinned pixel hash {pinned} cannot be checked"
    return None if actual == pinned else f"{name}: decoded-pixel SHA-256 is {actual}, the registry pins {pinned}"


def _verify_members(folder: Path, entry: RemoteFile) -> None:
    """After unpacking: every member with a pinned pixel hash is there and has it. On a failure the
    unpack marker and the failing files are removed (the next fetch unpacks afresh) and ChecksumError says why."""
    problems, bad = [], []
    for member, pinned in entry.members:
        path = folder / member
        problem = (f"{member} is not in {entry.name}" if not path.is_file()
                   else _check_pixels(path, member, pinned))
        if problem:
            problems.append(problem)
            bad.append(path)
    if problems:
        for path in bad:
            path.unlink(missing_ok=True)
        (folder / f".{Path(entry.name).name}.unpacked").unlink(missing_ok=True)
        raise ChecksumError(f"{entry.name}: {len(problems)} unpacked file(s) fail their pinned pixel hash:\n  "
                            + "\n  ".join(problems[:10]) + ("\n  ..." if len(problems) > 10 else "")
                            + "\nThose files were removed; if the server's data really changed, update the registry.")


def _unpack(folder: Path, entry: RemoteFile, sha256: str, say) -> None:
    """Unpack the verified archive once; on a later fetch, check that every file it unpacked is still
    there (a missing one is unpacked again) and has its size (one that differs is kept, and named)."""
    marker = folder / f".{Path(entry.name).name}.unpacked"
    if marker.exists() and regular_file(marker, "unpack marker").read_text().strip() == sha256:
        expected = archive_files(folder / entry.name)
        missing = sorted(name for name in expected if not (folder / name).is_file())
        changed = sorted(name for name, size in expected.items()
                         if name not in missing and (folder / name).stat().st_size != size)
        if changed:
            say(f"{entry.name}: {len(changed)} unpacked file(s) differ in size from the archive and are kept as they "
                f"are: {', '.join(changed[:5])}{' ...' if len(changed) > 5 else ''} (delete them and fetch again to "
                f"unpack them afresh)")
        if missing:
            say(f"{entry.name}: {len(missing)} unpacked file(s) missing ({', '.join(missing[:5])}"
                f"{' ...' if len(missing) > 5 else ''}); unpacking them again")
            safe_extract(folder / entry.name, folder, only=missing)
        return
    say(f"unpacking {entry.name} into {folder}")
    safe_extract(folder / entry.name, folder)
    write_bytes_atomic(marker, (sha256 + "\n").encode(), prefix=TEMP_PREFIX)


def check_names(folder: Path, dataset: Dataset, entries) -> None:
    """Every file (and pinned archive member) of ``entries`` stays inside the dataset folder
    (``download.entry_path``); else ``UnsafeNameError`` naming the entry, before anything is fetched."""
    for entry in entries:
        entry_path(folder, entry.name, f"{dataset.name} entry {entry.name!r}")
        for member, _ in entry.members:
            entry_path(folder, member, f"{dataset.name} entry {entry.name!r} (member {member!r})")


def _select(dataset: Dataset, only) -> list[RemoteFile]:
    if not only:
        return list(dataset.files)
    patterns = [only] if isinstance(only, str) else list(only)
    chosen = set(select_names([f.name for f in dataset.files], patterns))
    if not chosen:
        inside = [f.name for f in dataset.files if select_names([m for m, _ in f.members], patterns)]
        if inside:  # a scene of an archive: the archive holds every scene
            raise ValueError(f"only={patterns!r} names files inside the archive(s) {', '.join(inside)}, which hold "
                             f"every scene: fetch {dataset.name} without --only, or install from a local copy "
                             f"(--from DIR --only ...)")
        raise ValueError(f"only={patterns!r} matches none of {dataset.name}'s files (python -m data_fetch list "
                         f"{dataset.name} lists its scenes and files; --only takes a scene, a folder or a glob)")
    return [f for f in dataset.files if f.name in chosen]


def _download(folder: Path, entry: RemoteFile, known: str | None, retries: int, progressbar: bool,
              backoff: float) -> Path:
    path = folder / entry.name
    downloader = ResumableDownloader(path.with_name(path.name + ".part"), retries=retries,
                                     progressbar=progressbar, backoff=backoff)
    try:
        pooch.retrieve(entry.url, known_hash=known, fname=entry.name, path=folder, downloader=downloader)
    except ValueError as error:  # pooch: hash mismatch; its temporary file is already deleted
        if "hash" not in str(error).lower():
            raise
        raise ChecksumError(f"{entry.name}: {error}\nThe download was deleted (nothing is kept under its final "
                            f"name). If the server's file really changed, update the registry.") from None
    return path


def _set_aside(path: Path, name: str) -> Path:
    """Rename ``path`` to ``name`` beside it, or ``name-2``, ``name-3``, ...: never over an earlier one."""
    for number in itertools.count(1):
        aside = path.with_name(name if number == 1 else f"{name}-{number}")
        try:
            os.link(path, aside)  # fails if the name is taken: no race with another fetch
        except FileExistsError:
            continue
        except OSError:  # a file system without hard links
            if os.path.lexists(aside):
                continue
            os.replace(path, aside)
            return aside
        os.unlink(path)
        return aside


def _verify_manual(folder: Path, entry: RemoteFile, known: str) -> None:
    path = regular_file(folder / entry.name, "manual download")
    actual = pooch.file_hash(str(path), alg="sha256").lower()
    if actual != normal_sha256(known, entry.name):
        rejected = _set_aside(path, path.name + ".rejected")
        raise ChecksumError(f"{entry.name}: SHA-256 is {actual}, expected {known}. The file was moved to "
                            f"{rejected} (not deleted: it was yours); download it again.")


def fetch(dataset, dest=None, only=None, trust_first_download: bool = False, retries: int = 3,
          progressbar: bool = True, backoff: float = 1.0, say=print) -> list[Path]:
    """Fetch ``dataset`` (a name from ``DATASETS`` or a ``Dataset``) into ``<root>/<name>/``; returns
    the verified file paths. ``only``: glob pattern(s) on file names (e.g. ``"Adirondack-*"``).
    Raises ``UnpinnedFileError``, ``ChecksumError``, ``ManualDownloadRequired`` or ``FetchError``."""
    if isinstance(dataset, str):
        dataset = get_dataset(dataset)
    if not isinstance(dataset, Dataset):
        raise TypeError(f"dataset must be a name or a Dataset, got {type(dataset).__name__}")
    check_fetch_numbers(retries, backoff)  # before anything is looked at or fetched
    say = check_say(say)
    root = data_dir(dest)
    folder = entry_path(root, dataset.name, f"dataset {dataset.name!r}")
    for where in (root, folder):
        if where.exists() and not where.is_dir():
            raise FetchError(f"dest: {where} is a file; the data root and its dataset folders must be folders")
    entries = _select(dataset, only)
    check_names(folder, dataset, entries)
    _check_writable(folder)
    manual = dataset.manual is not None or any(f.url is None for f in entries)
    if manual:
        missing = [f.name for f in entries if not (folder / f.name).exists()]
        if missing:
            text = (dataset.manual or "Download these files by hand from {dest}.").format(dest=folder)
            raise ManualDownloadRequired(f"{text}\nStill missing in {folder}: {', '.join(missing)}")
    with install_lock(root, dataset.name, say):  # one install of this folder at a time: no record is lost
        remove_stale_temporaries(root, folder, [f.name for f in dataset.files], say)
        paths = _fetch_entries(folder, dataset, entries, manual, trust_first_download, retries, progressbar,
                               backoff, say)
        remove_spent_parts(paths)
    return paths


def _fetch_entries(folder: Path, dataset: Dataset, entries, manual: bool, trust_first_download: bool, retries: int,
                   progressbar: bool, backoff: float, say) -> list[Path]:
    """``fetch``'s work, under the install lock: each entry downloaded (or the user's file taken), verified,
    unpacked and, when trusted on first use, recorded; returns the verified paths."""
    paths = []
    for entry in entries:
        known = _known_hash(folder, entry, trust_first_download)
        existed = True  # a manual download is the user's file
        if manual:
            regular_file(folder / entry.name, "manual download")  # a FIFO would make the hashing wait forever
            if known is not None:
                _verify_manual(folder, entry, known)
        else:
            existed = os.path.lexists(folder / entry.name)
            if known is None and existed and not entry.pixel_sha256:
                # trust on first use covers what this fetch downloads, not whatever already sits there
                raise UnpinnedFileError(
                    f"{folder / entry.name} is already there, but no SHA-256 is pinned or recorded for it, so it "
                    f"cannot be verified; --trust-first-download trusts only bytes this fetch downloads. Move it "
                    f"away (or delete it) and fetch again.")
            _download(folder, entry, known, retries, progressbar, backoff)
        path = folder / entry.name
        if known is None and entry.pixel_sha256:  # verified by its decoded content, not taken on trust
            problem = _check_pixels(path, entry.name, entry.pixel_sha256)
            if problem:
                if manual or existed:
                    aside = _set_aside(path, path.name + ".rejected")
                    raise ChecksumError(f"{problem}. The file was moved to {aside} (not deleted: it was yours).")
                path.unlink(missing_ok=True)
                raise ChecksumError(f"{problem}. The download was deleted (nothing is kept under its final name).")
        trusted = known is None and not entry.pixel_sha256
        problem = content_problem(path, entry.name) if trusted else None  # the one verdict, before any trust
        if problem:
            if not manual:
                path.unlink(missing_ok=True)
            raise FetchError(f"{path}: {problem}{' as downloaded' if not manual else ''}; "
                             f"--trust-first-download records only a file that is what its name says. "
                             + ("Download it again by hand." if manual else "It was deleted; fetch again later."))
        digest = known or pooch.file_hash(str(path))
        if entry.unpack:
            try:
                _unpack(folder, entry, digest, say)
                _verify_members(folder, entry)
            except FetchError:
                if known is None and not manual:  # a download taken on trust and unusable: not kept
                    path.unlink(missing_ok=True)
                raise
        if trusted:  # trust on first use, recorded only once the file proved usable
            _record(folder, entry, digest, "trust-first-download",
                    "a manual download placed in this folder by the user" if manual
                    else f"downloaded by this fetch from {entry.url}")
            say(trusted_message(entry.name, digest, folder))
        paths.append(path)
    return paths

