"""Fit at a working size, fill at full size: how a full-size photo's holes get DDP's depth.

A DDP fit costs time and memory in proportion to its pixels (a 500×741 image at ``class``'s
widths needs minutes and gigabytes per fit on a CPU), while the holes of a depth map need far
less resolution than its valid pixels have. So: shrink the image and depth to a working size
(the longer side ``max_side``), fit there, bring the completed depth back to full size, and use
it only in the holes; the valid input pixels keep their exact values.

Depth is resampled in disparity (1/Z), as DDP fits it: on a plane disparity is affine in the
pixel coordinates, so linear up-sampling keeps a plane a plane (depth itself would bow).
Shrinking averages only the valid pixels of each block (a block less than half valid is a hole).
Pixel centres follow OpenCV's ``resize``: pixel (0, 0) is the centre of the top-left pixel, at
both sizes.
"""
from __future__ import annotations

import cv2
import numpy as np

__all__ = ["working_shape", "shrink", "fill_holes_at_full_size"]


def working_shape(shape, max_side: int) -> tuple[int, int]:
    """(H, W) scaled so that its longer side is at most ``max_side`` (aspect kept, sides ≥ 1).

    Example:
        >>> working_shape((500, 741), 128)
        (86, 128)
    """
    H, W = int(shape[0]), int(shape[1])
    if not (isinstance(max_side, (int, np.integer)) and max_side >= 1):
        raise ValueError(f"max_side must be a positive integer (pixels), got {max_side!r}")
    scale = min(1.0, max_side / max(H, W))
    return max(1, round(H * scale)), max(1, round(W * scale))


def shrink(rgb, depth, shape) -> tuple[np.ndarray, np.ndarray]:
    """``rgb`` (H, W, 3) and ``depth`` (H, W) metres, NaN = hole, resampled to ``shape`` (h, w).

    RGB by area averaging; depth in disparity, averaging the valid pixels of each block, NaN where
    less than half of a block is valid. Returns float32 arrays; the inputs are not modified.
    """
    depth = np.asarray(depth, dtype=np.float64)
    h, w = int(shape[0]), int(shape[1])
    if (h, w) == depth.shape:
        return np.asarray(rgb, np.float32).copy(), depth.astype(np.float32)
    valid = np.isfinite(depth) & (depth > 0)
    disparity = np.where(valid, 1.0 / np.where(valid, depth, 1.0), 0.0)
    summed = cv2.resize(disparity, (w, h), interpolation=cv2.INTER_AREA)
    weight = cv2.resize(valid.astype(np.float64), (w, h), interpolation=cv2.INTER_AREA)
    keep = weight >= 0.5
    small_depth = np.where(keep, weight / np.where(keep, summed, 1.0), np.nan).astype(np.float32)
    small_rgb = cv2.resize(np.asarray(rgb, np.float32), (w, h), interpolation=cv2.INTER_AREA)
    return np.clip(small_rgb, 0.0, 1.0), small_depth


def fill_holes_at_full_size(depth, filled_small, raw: bool = False) -> np.ndarray:
    """The full-size depth: ``depth`` (H, W) metres where valid, ``filled_small`` (h, w) metres
    (a completed depth, no NaN) up-sampled in disparity (bilinear) in the holes.

    Args:
        depth: the full-size input, NaN (or ≤ 0) = hole.
        filled_small: the completed depth at the working size.
        raw: return the up-sampled fill everywhere (the net's own output), not only in the holes.

    Returns:
        (H, W) float32 metres; without ``raw`` its valid pixels are exactly ``depth``'s.
    """
    depth = np.asarray(depth, dtype=np.float32)
    filled_small = np.asarray(filled_small, dtype=np.float64)
    if filled_small.ndim != 2 or not np.all(np.isfinite(filled_small) & (filled_small > 0)):
        raise ValueError("filled_small must be a (h, w) depth with finite values > 0 (a completed depth)")
    H, W = depth.shape
    disparity = cv2.resize(1.0 / filled_small, (W, H), interpolation=cv2.INTER_LINEAR)
    upsampled = (1.0 / disparity).astype(np.float32)
    if raw:
        return upsampled
    valid = np.isfinite(depth) & (depth > 0)
    return np.where(valid, depth, upsampled).astype(np.float32)
