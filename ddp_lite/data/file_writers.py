"""Arrays → image and depth-map files: PNG colour, 16-bit depth PNG, ``.npy``, PFM, COLMAP ``.bin``
(the formats, and their readers: :mod:`ddp_lite.data.fileio`).

Every depth writer stores a pixel that is no depth (NaN, inf, ≤ 0) as the format's hole value
(:func:`depth_units` for the integer formats, :func:`float_depth` for the float ones), never wrapped.
Writers work on bytes (``*_bytes``) so a caller writes them atomically
(``core.files.write_bytes_atomic``); ``write_*`` do that themselves.
"""
from __future__ import annotations

import io

import cv2
import numpy as np

from ..core.files import write_bytes_atomic

__all__ = ["depth_units", "float_depth", "npy_bytes", "rgb_png_bytes", "depth_png_bytes", "checked_depth_png_bytes",
           "pfm_bytes", "write_pfm", "colmap_depth_bytes", "write_colmap_depth"]


def depth_units(depth, factor: float, name: str = "depth") -> tuple[np.ndarray, int]:
    """(H, W) depth metres → (H, W) uint16 stored units (value = depth × ``factor``) and how many valid
    pixels do not fit.

    The one rule of every integer depth writer: a pixel that is no depth (NaN, ±inf, 0 or negative, e.g.
    a −1 "unknown" marker) is stored as 0, the format's "no value", never wrapped around the 16 bits (−1
    would become 65535 − 4999 = 12.107 m at TUM's 5000 per metre). A valid depth that rounds to 0 or to
    65535 or more does not fit: 0 is the hole value and 65535 the sentinel many cameras write for "no
    reading"; such pixels are stored as 0 and counted."""
    values = np.asarray(depth)
    if values.ndim != 2 or not (np.issubdtype(values.dtype, np.floating) or np.issubdtype(values.dtype, np.integer)):
        raise ValueError(f"{name} must be an (H, W) map of numbers (metres), got {values.dtype} {values.shape}")
    values = values.astype(np.float64)
    valid = np.isfinite(values) & (values > 0)
    scaled = np.round(np.where(valid, values, 0.0) * float(factor))
    lost = valid & ((scaled < 1) | (scaled >= 65535))
    return np.where(valid & ~lost, scaled, 0).astype(np.uint16), int(lost.sum())



def float_depth(depth, hole: float = np.nan, name: str = "depth") -> np.ndarray:
    """(H, W) depth → float32 with every pixel that is no depth (NaN, ±inf, 0 or negative, e.g. a −1
    marker) set to ``hole``: what every float depth writer stores (NaN for ``.npy``/``.pfm``, 0 for
    COLMAP's ``.bin``). A copy; the caller's array is untouched."""
    values = np.asarray(depth)
    if values.ndim != 2 or not (np.issubdtype(values.dtype, np.floating) or np.issubdtype(values.dtype, np.integer)):
        raise ValueError(f"{name} must be an (H, W) map of numbers (metres), got {values.dtype} {values.shape}")
    values = values.astype(np.float64)
    with np.errstate(over="ignore"):
        out = np.where(np.isfinite(values) & (values > 0), values, hole).astype(np.float32)
    return out



def npy_bytes(values) -> bytes:
    """Any array → the bytes of a ``.npy`` file (``np.load`` reads them back)."""
    buffer = io.BytesIO()
    np.save(buffer, values)
    return buffer.getvalue()



def rgb_png_bytes(rgb: np.ndarray) -> bytes:
    """(H, W, 3) float image in [0, 1] → 8-bit PNG bytes."""
    bgr = cv2.cvtColor(np.clip(rgb * 255.0 + 0.5, 0, 255).astype(np.uint8), cv2.COLOR_RGB2BGR)
    ok, buffer = cv2.imencode(".png", bgr)
    if not ok:
        raise RuntimeError("OpenCV could not encode a PNG")
    return buffer.tobytes()



def depth_png_bytes(depth, factor: float = 1000.0) -> tuple[bytes, int]:
    """(H, W) depth × ``factor`` (1000: millimetres) → (16-bit PNG bytes, how many valid pixels did not fit).
    No depth (NaN, inf, ≤ 0) becomes 0, the usual depth-PNG "no value"; so do valid depths that do not
    fit the 16 bits (:func:`depth_units`)."""
    units, lost = depth_units(depth, factor)
    ok, buffer = cv2.imencode(".png", units)
    if not ok:
        raise RuntimeError("OpenCV could not encode a 16-bit PNG")
    return buffer.tobytes(), lost



def checked_depth_png_bytes(depth: np.ndarray, factor: float, path_for_errors) -> bytes:
    """(H, W) depth × ``factor`` → 16-bit PNG bytes, no depth → 0; refuse valid values the format cannot hold."""
    png, lost = depth_png_bytes(depth, factor)
    if lost:
        values = np.asarray(depth, np.float64)
        valid = values[np.isfinite(values) & (values > 0)]
        raise ValueError(f"{path_for_errors}: depth in {valid.min():.4g}–{valid.max():.4g} m does not fit a 16-bit PNG at "
                         f"{factor:g} units per metre: {lost} value(s) outside the {1 / factor:.4g}–{65534 / factor:.4g} m "
                         f"it holds (0 and 65535 mean 'no reading'); use .npy, .pfm or .bin")
    return png



def pfm_bytes(values) -> bytes:
    """(H, W) or (H, W, 3) real values → the bytes of a little-endian float32 PFM file."""
    height, width = values.shape[:2]
    header = f"{'PF' if values.ndim == 3 else 'Pf'}\n{width} {height}\n-1.0\n".encode("ascii")
    return header + np.ascontiguousarray(np.flipud(values).astype("<f4")).tobytes()  # a copy: the input is untouched



def write_pfm(path, array) -> None:
    """Write (H, W), (H, W, 1) or (H, W, 3) real values as a little-endian float32 PFM, atomically."""
    values = np.asarray(array)
    if values.dtype == bool or not (np.issubdtype(values.dtype, np.integer) or np.issubdtype(values.dtype, np.floating)):
        raise ValueError(f"array must hold real numbers, got dtype {values.dtype}")
    if values.ndim == 3 and values.shape[2] == 1:
        values = values[:, :, 0]
    if not (values.ndim == 2 or (values.ndim == 3 and values.shape[2] == 3)) or min(values.shape[:2]) == 0:
        raise ValueError(f"array must be (H, W), (H, W, 1) or (H, W, 3), got shape {np.shape(array)}")
    write_bytes_atomic(path, pfm_bytes(values))



def colmap_depth_bytes(depth) -> bytes:
    """(H, W) depth → the bytes of a COLMAP dense ``.bin`` map (no depth, i.e. NaN, inf or ≤ 0, stored as 0,
    COLMAP's 'no depth')."""
    values = float_depth(depth, hole=0.0)
    H, W = values.shape
    return f"{W}&{H}&1&".encode("ascii") + np.ascontiguousarray(values.T).astype("<f4").tobytes()



def write_colmap_depth(path, depth) -> None:
    """Write (H, W) depth as a COLMAP dense ``.bin`` map, atomically."""
    write_bytes_atomic(path, colmap_depth_bytes(depth))
