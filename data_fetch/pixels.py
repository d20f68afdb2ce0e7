"""Hashes of what a file *holds* (decoded pixels, numbers, words), not of its bytes.

The dataset servers cannot be reached from the machines this kit is written on, so no byte hash of
an official file could be measured. Offline copies of many Middlebury files could be read, though,
and their *content* can be pinned: a PNG re-encoded at another compression level (or by another
encoder) has other bytes but the same pixels, so ``pixel_sha256`` gives it the same hash.

``pixel_sha256(path)`` is the SHA-256 of ``header + data`` where

* ``.png``: ``cv2.imread(path, cv2.IMREAD_UNCHANGED)`` (8- or 16-bit, grey, BGR or BGRA as OpenCV
  decodes it), kind ``png``;
* ``.pfm``: ``ddp_lite.data.fileio.read_pfm`` (float32, top row first whatever the file's row order
  and byte order), kind ``pfm``;
* ``.txt``: the text's tokens, kind ``text``, read as every text file of the kit is
  (``ddp_lite.core.files.read_text``: UTF-8 or UTF-16 with its byte-order mark, the mark dropped, CRLF → LF,
  so a copy saved by a Windows editor hashes the same): whitespace only separates tokens, and ``= [ ] ; ,``
  are tokens of their own, so ``doffs= 31.34`` and ``doffs=31.34``, or ``[ 1 0 ; 0 1 ]`` and
  ``[1 0; 0 1]``, are the same text; the tokens are joined by single spaces and hashed as UTF-8
  (an array of dtype ``|u1`` and shape ``(number of bytes,)``);

``data`` is the array's C-contiguous bytes in little-endian order and ``header`` is
``f"ddp-lite-pixels-v1\\nkind={kind}\\ndtype={dtype.str}\\nshape={'x'.join(map(str, shape))}\\n"``
(ASCII; ``dtype.str`` of the little-endian array, e.g. ``|u1``, ``<u2``, ``<f4``). So the hash
can be recomputed with numpy and hashlib alone (``reference_sha256``).
"""
from __future__ import annotations

import hashlib
import re
from pathlib import Path

import numpy as np

__all__ = ["pixel_sha256", "reference_sha256", "decode", "PIXEL_SUFFIXES", "text_sha256", "TEXT_SUFFIXES"]

PIXEL_SUFFIXES = (".png", ".pfm", ".txt")
TEXT_SUFFIXES = (".txt",)
_TOKEN = re.compile(r"[=\[\];,]|[^\s=\[\];,]+")


def reference_sha256(kind: str, array: np.ndarray) -> str:
    """The documented hash of ``array`` decoded from a file of ``kind`` (``png``, ``pfm`` or ``text``)."""
    if kind not in ("png", "pfm", "text"):
        raise ValueError(f"kind must be 'png', 'pfm' or 'text', got {kind!r}")
    array = np.asarray(array)
    little = np.ascontiguousarray(array.astype(array.dtype.newbyteorder("<"), copy=False))
    header = (f"ddp-lite-pixels-v1\nkind={kind}\ndtype={little.dtype.str}\n"
              f"shape={'x'.join(str(n) for n in little.shape)}\n").encode("ascii")
    return hashlib.sha256(header + little.tobytes()).hexdigest()


def decode(path) -> tuple[str, np.ndarray]:
    """``(kind, array)`` of ``path`` as ``pixel_sha256`` hashes it; ValueError if it cannot be read."""
    path = Path(path)
    suffix = path.suffix.lower()
    if suffix not in PIXEL_SUFFIXES:
        raise ValueError(f"path: {path} has no pixel hash (only {', '.join(PIXEL_SUFFIXES)} files do)")
    if not path.is_file():
        raise FileNotFoundError(f"path: {path} is not a file")
    if suffix == ".png":
        import cv2  # only when a PNG is hashed: `python -m data_fetch list` stays light

        array = cv2.imread(str(path), cv2.IMREAD_UNCHANGED)
        if array is None:
            raise ValueError(f"path: {path} could not be decoded as a PNG")
        return "png", array
    if suffix == ".pfm":
        from ddp_lite.data.fileio import read_pfm  # standard library + numpy; no torch

        return "pfm", read_pfm(path, "path")
    from ddp_lite.core.files import read_text  # standard library only

    text = read_text(path, "path")  # a byte-order mark dropped, CRLF → LF: an editor's copy is the same text
    return "text", np.frombuffer(" ".join(_TOKEN.findall(text)).encode("utf-8"), dtype=np.uint8)


def pixel_sha256(path) -> str:
    """SHA-256 (hex) of the decoded content of a ``.png``, ``.pfm`` or ``.txt`` file (see the module)."""
    kind, array = decode(path)
    return reference_sha256(kind, array)


def text_sha256(path) -> str | None:
    """For a text file (``TEXT_SUFFIXES``): SHA-256 of its text as the kit reads it (``core.files.read_text``: no
    byte-order mark, LF line ends), UTF-8 encoded, so the copies an editor saves hash alike; else (or not
    text) None."""
    if Path(path).suffix.lower() not in TEXT_SUFFIXES:
        return None
    from ddp_lite.core.files import read_text

    try:
        return hashlib.sha256(read_text(path, "path").encode("utf-8")).hexdigest()
    except ValueError:
        return None
