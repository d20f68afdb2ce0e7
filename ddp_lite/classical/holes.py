"""Holes and noise: how real depth sensors fail, applied to exact synthetic depth.

Every model here takes a depth map (H, W) in metres and returns ``(depth_with_nans, mask)``:
a float32 copy with NaN where the sensor gives no answer, and the bool mask (True = valid).
The input is never modified. Randomness comes only from ``seed``.

Stereo (SGM) holes come from a real matcher and live in ``stereo.py`` (``sgm_depth``).

**Synthetic holes.** ``random_holes`` removes smooth random blobs (a thresholded, blurred
noise field), ``stroke_holes`` paints thick brush strokes (the holes DepthComp cut into the
Middlebury disparities of the paper's Table 6), ``edge_band_holes`` removes a band across a depth discontinuity (where
depth-only completion bleeds foreground into background), and ``kinect_noise`` imitates a
structured-light sensor: noise growing as z², disparity quantised to 1/8 px, no reading out
of range, and dropouts along the far side of depth edges (the projector's shadow).
"""
from __future__ import annotations

import numpy as np
from scipy import ndimage

from ..core.checks import MIN_VALID_PIXELS, check_depth, check_int

__all__ = ["random_holes", "stroke_holes", "edge_band_holes", "kinect_noise", "hole_rim"]


def _check_depth(depth) -> np.ndarray:
    """The depth contract (``checks.check_depth``) for a hole model: any number of valid pixels."""
    return check_depth(depth, "depth", min_valid=0)


def random_holes(depth, fraction: float = 0.15, seed: int = 0, blob_size: float | None = None):
    """Remove smooth random blobs covering ``fraction`` of the (H, W) depth (metres) → (depth, mask);
    ``blob_size`` (px, default min(H, W)/16) is the blur scale of the noise field."""
    out = _check_depth(depth)
    if not 0.0 <= fraction < 1.0:
        raise ValueError(f"fraction must be in [0, 1), got {fraction!r}")
    H, W = out.shape
    blob_size = max(1.0, min(H, W) / 16.0) if blob_size is None else float(blob_size)
    if not np.isfinite(blob_size) or blob_size <= 0:
        raise ValueError(f"blob_size must be a positive number of pixels, got {blob_size!r}")
    rng = np.random.default_rng(check_int(seed, "seed", minimum=0))
    field = ndimage.gaussian_filter(rng.standard_normal((H, W)), blob_size, mode="wrap")  # (H, W) smooth
    if fraction > 0:
        out[field <= np.quantile(field, fraction)] = np.nan
    return out, np.isfinite(out)


def stroke_holes(depth, fraction: float = 0.085, seed: int = 0, width: float | None = None):
    """Remove thick brush strokes covering about ``fraction`` of the (H, W) depth (metres) → (depth, mask),
    DepthComp-style: each stroke a polyline of 1–2 segments (each H/10–H/5 long, turning by up to 90°),
    ``width`` px wide (default H/18, DepthComp's on Plastic), drawn until the fraction is reached."""
    import cv2  # drawing only; the module's other models need numpy and scipy alone

    out = _check_depth(depth)
    if not 0.0 <= fraction < 0.5:
        raise ValueError(f"fraction must be in [0, 0.5), got {fraction!r}")
    H, W = out.shape
    width = max(1.0, H / 18.0) if width is None else float(width)
    if not np.isfinite(width) or width <= 0:
        raise ValueError(f"width must be a positive number of pixels, got {width!r}")
    rng = np.random.default_rng(check_int(seed, "seed", minimum=0))
    canvas = np.zeros((H, W), np.uint8)
    thickness = max(1, int(round(width)))
    while fraction > 0 and canvas.mean() / 255.0 < fraction:
        point = rng.uniform((0.1 * W, 0.1 * H), (0.9 * W, 0.9 * H))
        angle = rng.uniform(0.0, 2.0 * np.pi)
        points = [point]
        for _ in range(int(rng.integers(1, 3))):
            angle += rng.uniform(-np.pi / 2, np.pi / 2)
            point = point + rng.uniform(H / 10, H / 5) * np.array([np.cos(angle), np.sin(angle)])
            points.append(point)
        cv2.polylines(canvas, [np.rint(np.array(points)).astype(np.int32)], False, 255, thickness, cv2.LINE_8)
    out[canvas > 0] = np.nan
    return out, np.isfinite(out)


def _depth_edges(depth: np.ndarray, threshold: float) -> np.ndarray:
    """(H, W) bool: pixels with a 4-neighbour whose depth differs by more than ``threshold`` (relative)."""
    edges = np.zeros(depth.shape, bool)
    for a, b, sa, sb in ((depth[:, 1:], depth[:, :-1], np.s_[:, 1:], np.s_[:, :-1]),
                         (depth[1:], depth[:-1], np.s_[1:], np.s_[:-1])):
        with np.errstate(invalid="ignore"):
            jump = np.abs(a - b) > threshold * np.fmin(a, b)  # NaN → False
        edges[sa] |= jump
        edges[sb] |= jump
    return edges


def edge_band_holes(depth, width: int | None = None, seed: int = 0, length: int | None = None,
                    n_bands: int = 1, threshold: float = 0.05):
    """Remove ``n_bands`` bands ``width`` px wide across depth edges (relative jump > ``threshold``),
    each along ``length`` px of edge, from (H, W) depth in metres → (depth, mask)."""
    out = _check_depth(depth)
    H, W = out.shape
    width = max(3, round(min(H, W) / 16)) if width is None else width
    length = max(8, min(H, W) // 3) if length is None else length
    for name, value in (("width", width), ("length", length), ("n_bands", n_bands)):
        if isinstance(value, bool) or int(value) != value or value < 1:
            raise ValueError(f"{name} must be a positive integer, got {value!r}")
    if not threshold > 0:
        raise ValueError(f"threshold must be positive, got {threshold!r}")
    rng = np.random.default_rng(check_int(seed, "seed", minimum=0))
    edges = _depth_edges(out, threshold)
    margin = int(width) // 2 + 1
    candidates = np.argwhere(edges[margin:H - margin, margin:W - margin]) + margin  # (M, 2) rows, cols
    if len(candidates) == 0:
        raise ValueError(f"depth has no depth edge (relative jump > threshold={threshold}) away from the border")
    rows, cols = np.mgrid[0:H, 0:W]
    band = np.zeros((H, W), bool)
    for _ in range(int(n_bands)):
        r, c = candidates[rng.integers(len(candidates))]
        segment = edges & ((rows - r) ** 2 + (cols - c) ** 2 <= (length / 2.0) ** 2)  # part of the edge
        band |= ndimage.distance_transform_edt(~segment) <= width / 2.0
    out[band] = np.nan
    return out, np.isfinite(out)


def kinect_noise(depth, seed: int = 0, sigma_coef: float = 1.5e-3, focal_px: float = 580.0,
                 baseline: float = 0.075, subpixel: int = 8, depth_range=(0.5, 8.0), edge_dropout: float = 0.6,
                 edge_width: int = 2, threshold: float = 0.05):
    """Kinect-v1-like reading of (H, W) depth in metres → (depth, mask): noise σ = sigma_coef·z²,
    disparity f·B/z quantised to 1/``subpixel`` px, NaN out of ``depth_range`` and, with
    probability ``edge_dropout``, within ``edge_width`` px on the far side of depth edges."""
    clean = _check_depth(depth).astype(np.float64)
    if not (sigma_coef >= 0 and focal_px > 0 and baseline > 0 and 0 <= edge_dropout <= 1):
        raise ValueError("need sigma_coef >= 0, focal_px > 0, baseline > 0 and edge_dropout in [0, 1]; got "
                         f"{sigma_coef}, {focal_px}, {baseline}, {edge_dropout}")
    if isinstance(subpixel, bool) or int(subpixel) != subpixel or subpixel < 1:
        raise ValueError(f"subpixel must be a positive integer, got {subpixel!r}")
    if int(edge_width) != edge_width or edge_width < 0:
        raise ValueError(f"edge_width must be a non-negative integer, got {edge_width!r}")
    near, far = depth_range
    if not 0 < near < far:
        raise ValueError(f"depth_range must be (near, far) with 0 < near < far, got {depth_range!r}")
    rng = np.random.default_rng(check_int(seed, "seed", minimum=0))
    noisy = clean + rng.standard_normal(clean.shape) * sigma_coef * clean ** 2  # axial noise ∝ z²
    fb = focal_px * baseline
    with np.errstate(divide="ignore", invalid="ignore"):
        disparity = np.round(fb / noisy * subpixel) / subpixel  # the sensor's 1/8-px disparity steps
        out = fb / disparity
    out[~((out >= near) & (out <= far))] = np.nan  # also NaN, inf from disparity 0
    if edge_width > 0 and edge_dropout > 0:
        filled = np.where(np.isfinite(clean), clean, np.inf)
        nearest = ndimage.minimum_filter(filled, size=2 * int(edge_width) + 1)  # (H, W) nearest neighbour depth
        shadow = nearest < clean * (1.0 - threshold)  # a much nearer surface is close by: far side of an edge
        out[shadow & (rng.random(clean.shape) < edge_dropout)] = np.nan
    out = out.astype(np.float32)
    return out, np.isfinite(out)


def hole_rim(valid: np.ndarray, width: int) -> np.ndarray:
    """(H, W) bool: the ``valid`` pixels within ``width`` px (4-connected steps) of a hole; none where
    ``width`` is 0, where there is no hole, or where fewer than ``MIN_VALID_PIXELS`` valid pixels would be left.

    Example:
        >>> valid = np.ones((5, 5), bool); valid[2, 2] = False
        >>> int(hole_rim(valid, 1).sum())
        4
    """
    if width == 0 or valid.all():
        return np.zeros_like(valid)
    rim = ndimage.binary_dilation(~valid, iterations=width) & valid
    return rim if (valid & ~rim).sum() >= MIN_VALID_PIXELS else np.zeros_like(valid)
