"""A resumable HTTP downloader for pooch (``pooch.retrieve(..., downloader=ResumableDownloader(part))``).

pooch's own ``HTTPDownloader`` starts again from byte 0 after a dropped connection. This one
streams into a stable ``<file>.part`` next to the target; a retry (in the same call, or a later
``fetch``) asks the server for the rest with ``Range: bytes=<size of .part>-`` **and** ``If-Range``
carrying the validator (strong ETag, else Last-Modified) that the server sent with the first
bytes, kept in ``<file>.part.json``. If the server's file changed since, HTTP answers with the
whole new file (200) and the download starts again from zero; a ``.part`` without a validator is
never resumed. So a resumed file is never spliced from two versions. When the file is complete
the ``.part`` is moved onto pooch's temporary file, pooch checks the SHA-256, and only then
renames it to its final name; on a mismatch pooch deletes it, so neither the final name nor the
``.part`` holds bad bytes.
"""
from __future__ import annotations

import json
import math
import os
import time
from pathlib import Path

import requests
import urllib3
from tqdm.auto import tqdm

from ddp_lite.core.files import regular_file

__all__ = ["FetchError", "ChecksumError", "UnsafeNameError", "ResumableDownloader", "entry_path", "normal_sha256",
           "content_problem", "check_fetch_numbers"]


class FetchError(RuntimeError):
    """A dataset could not be fetched (offline, HTTP error, unsafe archive, unpinned file, ...)."""


class ChecksumError(FetchError):
    """A file's SHA-256 differs from the pinned or recorded one."""


class UnsafeNameError(FetchError, ValueError):
    """A registry entry names a file outside its dataset folder (absolute, ``..``, a link out of it)."""


def entry_path(folder, name: str, entry: str) -> Path:
    """``folder / name`` for a registry entry's file (or an archive member it pins), refused with
    :class:`UnsafeNameError` naming ``entry`` unless it stays inside ``folder`` (no absolute path, no
    ``..``, no symbolic link leading out): the one guard every fetched or installed name passes."""
    from ddp_lite.core.files import PathEscapeError, path_inside
    if not isinstance(name, str):
        raise UnsafeNameError(f"{entry}: the file name must be a string, got {type(name).__name__}")
    try:
        return path_inside(folder, name, f"{entry}: file name", links=True)
    except PathEscapeError as error:
        raise UnsafeNameError(f"{error}. The registry entry is refused: nothing was downloaded, verified or "
                              f"returned for it") from None


def normal_sha256(value, what: str) -> str | None:
    """A SHA-256 as the kit compares it: 64 lower-case hex digits (a ``sha256:`` prefix and upper case
    accepted and normalised, once, here); None stays None; anything else → ValueError naming ``what``."""
    if value is None:
        return None
    text = value.strip().lower() if isinstance(value, str) else None
    if text is not None and text.startswith("sha256:"):
        text = text[len("sha256:"):]
    if text is None or len(text) != 64 or any(c not in "0123456789abcdef" for c in text):
        raise ValueError(f"{what} must be a SHA-256 (64 hex digits), got {value!r}")
    return text


# What a file's first bytes must be, by the ending of its name: a server's HTML error page saved as
# "view1.png" is not a PNG, whatever its hash is.
_MAGIC = (
    ((".png",), (b"\x89PNG\r\n\x1a\n",), "a PNG"),
    ((".jpg", ".jpeg"), (b"\xff\xd8\xff",), "a JPEG"),
    ((".zip",), (b"PK\x03\x04", b"PK\x05\x06"), "a ZIP archive"),
    ((".tar.gz", ".tgz", ".gz"), (b"\x1f\x8b",), "a gzip file"),
    ((".tar.bz2", ".bz2"), (b"BZh",), "a bzip2 file"),
    ((".tar.xz", ".xz"), (b"\xfd7zXZ\x00",), "an xz file"),
    ((".7z",), (b"7z\xbc\xaf\x27\x1c",), "a 7-Zip archive"),
    ((".pfm",), (b"PF\n", b"Pf\n", b"PF\r", b"Pf\r", b"PF ", b"Pf "), "a PFM image"),
    ((".mat",), (b"MATLAB", b"\x89HDF\r\n\x1a\n"), "a MATLAB file"),
    ((".h5", ".hdf5"), (b"\x89HDF\r\n\x1a\n",), "an HDF5 file"),
    ((".npy",), (b"\x93NUMPY",), "a NumPy file"),
    ((".tif", ".tiff"), (b"II*\x00", b"MM\x00*"), "a TIFF image"),
    ((".exr",), (b"\x76\x2f\x31\x01",), "an OpenEXR image"),
    ((".pgm",), (b"P5", b"P2"), "a PGM image"),
    ((".ppm",), (b"P6", b"P3"), "a PPM image"),
    ((".ply",), (b"ply",), "a PLY file"),
)


def content_problem(path, name: str) -> str | None:
    """The one verdict on what arrived, before it is trusted or recorded: None if ``path``'s first bytes
    are what its ``name`` says (a ``.png`` starts with PNG's signature, a ``.zip`` with ``PK``, ...) and
    it is not empty; else a sentence saying what it is instead (an HTML page: an error or login page)."""
    with open(regular_file(path, name), "rb") as handle:
        head = handle.read(512)
    if not head:
        return f"{name} is empty (0 bytes)"
    lower = name.lower()
    stripped = head.lstrip().lower()
    html = stripped.startswith((b"<!doctype html", b"<html", b"<head", b"<body", b"<?xml", b"<!--"))
    looks = (f"an HTML page (starts {head[:40]!r}: the server's error or login page?)" if html
             else f"something else (starts {head[:16]!r})")
    if lower.endswith(".txt") and not html:  # a text file: UTF-8 (or UTF-16 with its BOM) and no NUL bytes
        from ddp_lite.core.files import NotTextError, read_text
        try:
            read_text(path, name)
        except NotTextError as error:
            return str(error).replace(f"{name}: {path} ", f"{name} ", 1)
        return None
    if lower.endswith(".tar"):
        return None if head[257:262] == b"ustar" else f"{name} is not a tar archive: it is {looks}"
    for endings, signatures, kind in _MAGIC:
        if lower.endswith(endings):
            return None if head.startswith(signatures) else f"{name} is not {kind}: it is {looks}"
    if html and not lower.endswith((".html", ".htm", ".xml", ".svg")):
        return f"{name} is {looks}"
    return None


def check_fetch_numbers(retries, backoff=1.0, timeout=30.0) -> None:
    """Refuse, before anything is fetched, a number that makes no sense (ValueError naming it)."""
    if isinstance(retries, bool) or not isinstance(retries, (int, float)) or not math.isfinite(retries) \
            or int(retries) != retries or retries < 0:
        raise ValueError(f"retries must be an integer 0 or more, got {retries!r}")
    for name, value, zero in (("backoff", backoff, True), ("timeout", timeout, False)):
        if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value) \
                or value < 0 or (value == 0 and not zero):
            raise ValueError(f"{name} must be a finite number of seconds {'≥ 0' if zero else '> 0'}, got {value!r}")


class _Incomplete(Exception):
    """The server closed the stream before the announced size arrived."""


def _validator(response: requests.Response) -> str | None:
    """What ``If-Range`` may carry for this response: a strong ETag, else Last-Modified, else None."""
    etag = response.headers.get("ETag")
    if etag and not etag.startswith("W/"):
        return etag
    return response.headers.get("Last-Modified")


def _total_size(response: requests.Response, offset: int) -> int | None:
    """Full file size in bytes from Content-Range (206) or Content-Length (200), else None."""
    content_range = response.headers.get("Content-Range", "")
    if "/" in content_range and not content_range.endswith("/*"):
        return int(content_range.rsplit("/", 1)[1])
    length = response.headers.get("Content-Length")
    return None if length is None else int(length) + (offset if response.status_code == 206 else 0)


class ResumableDownloader:
    """pooch downloader: GET ``url`` into ``part`` (bytes kept across failures), resume with HTTP
    Range, retry ``retries`` times on connection errors (wait ``backoff``·2^k s), tqdm progress."""

    def __init__(self, part, retries: int = 3, timeout: float = 30.0, progressbar: bool = True,
                 backoff: float = 1.0, chunk_size: int = 1 << 16):
        check_fetch_numbers(retries, backoff, timeout)
        if isinstance(chunk_size, bool) or not isinstance(chunk_size, int) or chunk_size < 1:
            raise ValueError(f"chunk_size must be a positive integer, got {chunk_size!r}")
        self.part = Path(part)
        self.retries, self.timeout, self.progressbar = int(retries), float(timeout), bool(progressbar)
        self.backoff, self.chunk_size = float(backoff), int(chunk_size)

    def __call__(self, url: str, output_file, pooch=None, check_only: bool = False):
        if check_only:  # pooch's "is this URL available?" protocol
            try:
                return requests.head(url, timeout=self.timeout, allow_redirects=True).ok
            except requests.RequestException:
                return False
        self.part.parent.mkdir(parents=True, exist_ok=True)
        for kept in (self.part, self._meta):  # a FIFO there would block the first write (or read) for ever
            if os.path.lexists(kept):
                try:
                    regular_file(kept, "download in progress")
                except (ValueError, OSError) as error:
                    raise FetchError(f"{error}; it is not a partial download: delete it and fetch again") from None
        for attempt in range(self.retries + 1):
            try:
                self._attempt(url)
                break
            except (requests.ConnectionError, requests.Timeout, requests.exceptions.ChunkedEncodingError,
                    urllib3.exceptions.HTTPError, _Incomplete) as error:
                have = self.part.stat().st_size if self.part.exists() else 0
                if attempt == self.retries:
                    host = requests.utils.urlparse(url).netloc
                    resumable = have and self._resume_from(url)[0]
                    kept = (f"{have} bytes are kept in {self.part}; the next fetch resumes from there "
                            f"if the server's file has not changed." if resumable
                            else f"{have} bytes arrived, but the server sent no ETag/Last-Modified to resume "
                                 f"them safely; the next fetch starts again." if have else "Nothing was downloaded.")
                    raise FetchError(f"could not download {url} after {attempt + 1} attempt(s): {error}.\n"
                                     f"Is this machine offline, or is {host} down? {kept}") from None
                time.sleep(self.backoff * 2 ** attempt)
        os.replace(self.part, output_file)
        self._forget()

    @property
    def _meta(self) -> Path:
        return self.part.with_name(self.part.name + ".json")

    def _forget(self) -> None:
        """Drop the ``.part`` validator record (the ``.part`` itself is gone or restarted)."""
        self._meta.unlink(missing_ok=True)

    def _resume_from(self, url: str) -> tuple[int, dict]:
        """(offset, validator record) of the ``.part``; (0, {}) when it cannot be resumed safely."""
        offset = self.part.stat().st_size if self.part.exists() else 0
        try:
            meta = json.loads(self._meta.read_text()) if offset else {}
        except (OSError, ValueError):
            meta = {}
        if not offset or not isinstance(meta, dict) or meta.get("url") != url or not meta.get("validator"):
            return 0, {}  # no proof that the bytes kept are from the file the server has now
        return offset, meta

    def _attempt(self, url: str) -> None:
        """One GET; appends to ``part`` when the server confirms (206 + same validator) it is the same file."""
        offset, meta = self._resume_from(url)
        headers = {"Accept-Encoding": "identity"}  # byte offsets must be offsets into the file itself
        if offset:
            headers["Range"] = f"bytes={offset}-"
            headers["If-Range"] = meta["validator"]
        with requests.get(url, headers=headers, stream=True, timeout=self.timeout) as response:
            if response.status_code == 416 and offset:  # nothing left to send, or the file changed
                total = _total_size(response, 0)
                if total == offset and total == meta.get("size"):
                    return
                self.part.unlink()
                self._forget()
                raise _Incomplete(f"the server rejected a resume at byte {offset}; starting again")
            if response.status_code >= 400:
                if response.status_code >= 500:
                    raise requests.ConnectionError(f"HTTP {response.status_code} from the server")
                raise FetchError(f"{url} answered HTTP {response.status_code} {response.reason}; "
                                 f"check the URL or whether the file needs a manual download")
            resumed = response.status_code == 206 and offset > 0
            total = _total_size(response, offset if resumed else 0)
            if resumed and (_validator(response) not in (None, meta["validator"]) or total != meta.get("size")):
                # a server that honours Range but ignores If-Range, serving a changed file
                self.part.unlink()
                self._forget()
                raise _Incomplete(f"{url} changed on the server since byte {offset} arrived; starting again")
            if not resumed:
                record = {"url": url, "validator": _validator(response), "size": total}
                self._meta.write_text(json.dumps(record))
            done = offset if resumed else 0
            with open(self.part, "ab" if resumed else "wb") as handle, \
                    tqdm(total=total, initial=done, unit="B", unit_scale=True, unit_divisor=1024,
                         desc=self.part.name[:-5], disable=not self.progressbar, leave=False) as bar:
                while True:  # read1: whatever has arrived, so a dropped connection loses no received bytes
                    chunk = response.raw.read1(self.chunk_size)
                    if not chunk:
                        break
                    handle.write(chunk)
                    bar.update(len(chunk))
                    done += len(chunk)
            if total is not None and done != total:
                raise _Incomplete(f"got {done} of {total} bytes")
