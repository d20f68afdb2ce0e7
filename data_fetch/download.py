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
import os
import time
from pathlib import Path

import requests
import urllib3
from tqdm.auto import tqdm

from ddp_lite.core.files import regular_file

__all__ = ["FetchError", "ChecksumError", "ResumableDownloader"]


class FetchError(RuntimeError):
    """A dataset could not be fetched (offline, HTTP error, unsafe archive, unpinned file, ...)."""


class ChecksumError(FetchError):
    """A file's SHA-256 differs from the pinned or recorded one."""


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
        if int(retries) != retries or retries < 0:
            raise ValueError(f"retries must be a non-negative integer, got {retries!r}")
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
