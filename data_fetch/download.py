"""A resumable HTTP downloader for pooch (``pooch.retrieve(..., downloader=ResumableDownloader(part))``).

pooch's own ``HTTPDownloader`` starts again from byte 0 after a dropped connection. This one
streams into a stable ``<file>.part`` next to the target; a retry (in the same call, or a later
``fetch``) asks the server for the rest with ``Range: bytes=<size of .part>-``. When the file is
complete the ``.part`` is moved onto pooch's temporary file, pooch checks the SHA-256, and only
then renames it to its final name; on a mismatch pooch deletes it, so neither the final name
nor the ``.part`` holds bad bytes.
"""
from __future__ import annotations

import os
import time
from pathlib import Path

import requests
import urllib3
from tqdm.auto import tqdm

__all__ = ["FetchError", "ChecksumError", "ResumableDownloader"]


class FetchError(RuntimeError):
    """A dataset could not be fetched (offline, HTTP error, unsafe archive, unpinned file, ...)."""


class ChecksumError(FetchError):
    """A file's SHA-256 differs from the pinned or recorded one."""


class _Incomplete(Exception):
    """The server closed the stream before the announced size arrived."""


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
        for attempt in range(self.retries + 1):
            try:
                self._attempt(url)
                break
            except (requests.ConnectionError, requests.Timeout, requests.exceptions.ChunkedEncodingError,
                    urllib3.exceptions.HTTPError, _Incomplete) as error:
                have = self.part.stat().st_size if self.part.exists() else 0
                if attempt == self.retries:
                    host = requests.utils.urlparse(url).netloc
                    kept = (f"{have} bytes are kept in {self.part}; the next fetch resumes from there." if have
                            else "Nothing was downloaded.")
                    raise FetchError(f"could not download {url} after {attempt + 1} attempt(s): {error}.\n"
                                     f"Is this machine offline, or is {host} down? {kept}") from None
                time.sleep(self.backoff * 2 ** attempt)
        os.replace(self.part, output_file)

    def _attempt(self, url: str) -> None:
        """One GET; appends to ``part`` when the server honours Range, else starts over."""
        offset = self.part.stat().st_size if self.part.exists() else 0
        headers = {"Accept-Encoding": "identity"}  # byte offsets must be offsets into the file itself
        if offset:
            headers["Range"] = f"bytes={offset}-"
        with requests.get(url, headers=headers, stream=True, timeout=self.timeout) as response:
            if response.status_code == 416 and offset:  # nothing left to send, or the file changed
                total = _total_size(response, 0)
                if total == offset:
                    return
                self.part.unlink()
                raise _Incomplete(f"the server rejected a resume at byte {offset}; starting again")
            if response.status_code >= 400:
                if response.status_code >= 500:
                    raise requests.ConnectionError(f"HTTP {response.status_code} from the server")
                raise FetchError(f"{url} answered HTTP {response.status_code} {response.reason}; "
                                 f"check the URL or whether the file needs a manual download")
            resumed = response.status_code == 206 and offset > 0
            total = _total_size(response, offset if resumed else 0)
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
