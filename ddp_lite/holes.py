"""Holes and noise: how real depth sensors fail, applied to exact synthetic depth.

Every model here takes a depth map (H, W) in metres and returns ``(depth_with_nans, mask)``:
a float32 copy with NaN where the sensor gives no answer, and the bool mask (True = valid).
The input is never modified. Randomness comes only from ``seed``.

**Stereo (SGM).** A rectified pair sees a point at column u in the left image and at
``u - d`` in the right one; the disparity ``d = f·B / z`` (focal f in pixels, baseline B in
metres) gives depth ``z = f·B / d``. Semi-Global Matching (Hirschmüller 2008; OpenCV's
``StereoSGBM``) compares small blocks along each row and adds smoothness along several
directions. It fails in predictable places, which is what makes its holes realistic:

- *no texture* (sky, painted walls): every disparity costs the same; the **uniqueness** test
  (the best cost must beat the second best by a margin) throws such pixels away (paper Fig. 3);
- *occlusions*: a background point hidden behind an object in the right view has no match; the
  **left-right check** catches it: match right→left as well and keep a pixel only if both
  directions agree within 1 px. (OpenCV computes the right disparity for us if we flip both
  images horizontally and swap them: the flipped right image becomes a "left" image.);
- *small wrong islands*: **speckle filtering** removes connected blobs of few pixels whose
  disparity differs from their surroundings;
- *the image border*: a point near the left edge of the left image falls outside the right one.
  We pad both images on the left before matching so that OpenCV does not blank a whole strip of
  ``numDisparities`` columns, and then drop only pixels whose match would lie outside the image.

Two parameter sets mirror the paper's ELAS ``params1``/``params2`` on KITTI: ``"dense"``
(lenient: few holes) and ``"sparse"`` (strict uniqueness, larger speckle windows and a minimum
local texture, as ELAS's ``support_texture``: many holes).

**Synthetic holes.** ``random_holes`` removes smooth random blobs (a thresholded, blurred
noise field), ``edge_band_holes`` removes a band across a depth discontinuity (where
depth-only completion bleeds foreground into background), and ``kinect_noise`` imitates a
structured-light sensor: noise growing as z², disparity quantised to 1/8 px, no reading out
of range, and dropouts along the far side of depth edges (the projector's shadow).
"""
from __future__ import annotations

import cv2
import numpy as np
from scipy import ndimage

from .scenes import Scene

__all__ = ["SGM_PARAMS", "sgm_disparity", "sgm_depth", "gt_disparity", "random_holes", "edge_band_holes",
           "kinect_noise"]

# block: SAD window (px); uniqueness: % margin; speckle_window: fraction of the image area;
# speckle_range: px; texture: minimum mean |∂I/∂x| (8-bit levels) in the block, 0 = off.
SGM_PARAMS = {
    "dense": dict(block=5, uniqueness=5, speckle_window=0.002, speckle_range=2, texture=0.0, p1=8, p2=32),
    "sparse": dict(block=5, uniqueness=20, speckle_window=0.008, speckle_range=1, texture=4.0, p1=8, p2=48),
}


def _check_depth(depth, name: str = "depth") -> np.ndarray:
    """A float32 copy of a (H, W) depth map in metres (NaN holes), or a ValueError naming ``name``."""
    array = np.asarray(depth)
    if array.ndim != 2:
        raise ValueError(f"{name} must be (H, W) metres, got shape {array.shape}")
    if not np.issubdtype(array.dtype, np.floating):
        raise ValueError(f"{name} must be float metres with NaN holes, got dtype {array.dtype}")
    array = array.astype(np.float32, copy=True)
    if np.isinf(array).any():
        raise ValueError(f"{name} contains inf; mark holes with NaN")
    if (array[np.isfinite(array)] <= 0).any():
        raise ValueError(f"{name} must be positive (metres) where it is valid")
    return array


def _check_seed(seed) -> int:
    if isinstance(seed, bool) or int(seed) != seed or seed < 0:
        raise ValueError(f"seed must be a non-negative integer, got {seed!r}")
    return int(seed)


def _stereo_pair(scene, ref):
    if not isinstance(scene, Scene):
        raise TypeError(f"scene must be a ddp_lite.Scene, got {type(scene).__name__}")
    if not scene.right or len(scene.right) != len(scene.views):
        raise ValueError("scene has no rectified right views (scene.right); SGM needs a stereo pair per view")
    if isinstance(ref, bool) or int(ref) != ref or not 0 <= ref < len(scene):
        raise ValueError(f"ref must be a view index in [0, {len(scene)}), got {ref!r}")
    if "baseline" not in scene.meta or scene.meta["baseline"] <= 0:
        raise ValueError("scene.meta['baseline'] must be a positive stereo baseline in metres")
    return scene.views[int(ref)], scene.right[int(ref)], float(scene.meta["baseline"])


def _params(params) -> dict:
    if isinstance(params, str):
        if params not in SGM_PARAMS:
            raise ValueError(f"params must be one of {sorted(SGM_PARAMS)} or a dict, got {params!r}")
        return dict(SGM_PARAMS[params])
    if isinstance(params, dict):
        unknown = set(params) - set(SGM_PARAMS["dense"])
        if unknown:
            raise ValueError(f"params has unknown keys {sorted(unknown)}; known: {sorted(SGM_PARAMS['dense'])}")
        return {**SGM_PARAMS["dense"], **params}
    raise ValueError(f"params must be 'dense', 'sparse' or a dict, got {params!r}")


def _gray8(rgb: np.ndarray) -> np.ndarray:
    """(H, W, 3) float [0, 1] → (H, W) uint8 luminance."""
    return cv2.cvtColor(np.clip(rgb * 255.0 + 0.5, 0, 255).astype(np.uint8), cv2.COLOR_RGB2GRAY)


def _match(left: np.ndarray, right: np.ndarray, num_disp: int, p: dict) -> np.ndarray:
    """One SGBM pass on uint8 (H, W) images → left disparity (H, W) float px, NaN = no answer."""
    H, W = left.shape
    block = int(p["block"])
    area = block * block
    matcher = cv2.StereoSGBM_create(
        minDisparity=0, numDisparities=num_disp, blockSize=block, P1=p["p1"] * area, P2=p["p2"] * area,
        disp12MaxDiff=-1, uniquenessRatio=int(p["uniqueness"]),
        speckleWindowSize=int(round(p["speckle_window"] * H * W)), speckleRange=int(p["speckle_range"]),
        preFilterCap=31, mode=cv2.STEREO_SGBM_MODE_SGBM)
    pad = num_disp + block  # left padding, so OpenCV does not blank the first num_disp columns
    lp = cv2.copyMakeBorder(left, 0, 0, pad, 0, cv2.BORDER_REPLICATE)
    rp = cv2.copyMakeBorder(right, 0, 0, pad, 0, cv2.BORDER_REPLICATE)
    raw = matcher.compute(lp, rp)[:, pad:].astype(np.float32) / 16.0  # fixed point, 4 fractional bits
    disparity = np.where(raw > 0, raw, np.nan)  # ≤ 0: no answer (or a point at infinity)
    u = np.arange(W, dtype=np.float32)[None, :]
    disparity[u - disparity < -0.5] = np.nan  # the match would lie outside the right image
    if p["texture"] > 0:  # ELAS-style support texture: flat blocks give no answer
        grad = np.abs(cv2.Sobel(left, cv2.CV_32F, 1, 0, ksize=3)) / 4.0
        disparity[cv2.blur(grad, (block, block)) < p["texture"]] = np.nan
    return disparity


def _num_disparities(f: float, baseline: float, d_min: float, width: int) -> int:
    """Disparity search range: a multiple of 16 covering f·B / d_min (the nearest depth)."""
    largest = f * baseline / d_min + 2.0
    return int(min(max(16, 16 * np.ceil(largest / 16.0)), 16 * max(1, width // 32)))


def sgm_disparity(scene, ref: int, params="dense"):
    """SGM on view ``ref``'s rectified pair → disparity (H, W) float32 px (NaN holes), mask (H, W) bool."""
    left_view, right_view, baseline = _stereo_pair(scene, ref)
    p = _params(params)
    f = float(left_view.camera.K[0, 0])
    d_min = float(scene.meta.get("d_min", np.nanmin(left_view.depth)))
    left, right = _gray8(left_view.rgb), _gray8(right_view.rgb)  # (H, W) uint8
    num_disp = _num_disparities(f, baseline, d_min, left.shape[1])
    disp_left = _match(left, right, num_disp, p)
    # right disparity: flip both images, swap their roles, flip the answer back
    disp_right = _match(right[:, ::-1].copy(), left[:, ::-1].copy(), num_disp, p)[:, ::-1]
    H, W = left.shape
    rows = np.arange(H)[:, None].repeat(W, 1)
    target = np.round(np.arange(W)[None, :] - np.nan_to_num(disp_left, nan=0.0)).astype(int)  # (H, W) column in right
    inside = (target >= 0) & (target < W)
    back = np.full((H, W), np.nan, np.float32)
    back[inside] = disp_right[rows[inside], target[inside]]
    consistent = np.abs(disp_left - back) <= 1.0  # NaN on either side → False
    disparity = np.where(consistent, disp_left, np.nan).astype(np.float32)
    return disparity, np.isfinite(disparity)


def sgm_depth(scene, ref: int, params="dense"):
    """SGM depth of view ``ref`` → depth (H, W) float32 metres (NaN holes), mask (H, W) bool;
    z = f·B/(d + doffs), ``doffs`` = ``scene.meta["doffs"]`` (Middlebury's principal-point offset, 0 if absent)."""
    disparity, mask = sgm_disparity(scene, ref, params)
    f, baseline = float(scene.views[ref].camera.K[0, 0]), float(scene.meta["baseline"])
    shifted = disparity + float(scene.meta.get("doffs", 0.0))
    mask = mask & (shifted > 0)
    depth = np.full(disparity.shape, np.nan, np.float32)
    depth[mask] = f * baseline / shifted[mask]
    return depth, mask


def gt_disparity(scene, ref: int) -> np.ndarray:
    """Ground-truth disparity of view ``ref`` (H, W) float32 px: f·B / depth − doffs (for KITTI's D1)."""
    view, _, baseline = _stereo_pair(scene, ref)
    doffs = float(scene.meta.get("doffs", 0.0))
    return (float(view.camera.K[0, 0]) * baseline / view.depth.astype(np.float64) - doffs).astype(np.float32)


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
    rng = np.random.default_rng(_check_seed(seed))
    field = ndimage.gaussian_filter(rng.standard_normal((H, W)), blob_size, mode="wrap")  # (H, W) smooth
    if fraction > 0:
        out[field <= np.quantile(field, fraction)] = np.nan
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
    rng = np.random.default_rng(_check_seed(seed))
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
    rng = np.random.default_rng(_check_seed(seed))
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
