"""Stereo: semi-global matching on a rectified pair, and pixel disparity ↔ depth.

A rectified pair sees a point at column u in the left image and at
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

**Pixel disparity.** ``pixel_disparity`` and ``disparity_to_depth`` convert between depth z (metres)
and disparity d (pixels of the rectified pair) with ``d = f·B / z − doffs`` (``doffs`` = Middlebury's
principal-point offset ``cx1 − cx0``, 0 for the synthetic scenes and KITTI). Not to be confused with
DDP's *normalised* disparity in [0, 1] (``disparity.DisparityTransform``), which is what the net fits.
"""
from __future__ import annotations

import cv2
import numpy as np

from ..core.views import Scene

__all__ = ["SGM_PARAMS", "sgm_disparity", "sgm_left_right_failures", "sgm_depth", "sgm_depth_subsampled", "gt_disparity", "pixel_disparity",
           "disparity_to_depth"]

# block: SAD window (px); uniqueness: % margin; speckle_window: fraction of the image area;
# speckle_range: px; texture: minimum mean |∂I/∂x| (8-bit levels) in the block, 0 = off.
SGM_PARAMS = {
    "dense": dict(block=5, uniqueness=5, speckle_window=0.002, speckle_range=2, texture=0.0, p1=8, p2=32),
    "sparse": dict(block=5, uniqueness=20, speckle_window=0.008, speckle_range=1, texture=4.0, p1=8, p2=48),
}


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


def _left_right(scene, ref: int, params):
    """SGBM both ways on view ``ref``'s pair → left disparity (H, W) px (NaN: no answer) and (H, W) bool:
    the left-right check passed (the right image's match points back within 1 px)."""
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
    return disp_left, np.abs(disp_left - back) <= 1.0  # NaN on either side → False


def sgm_disparity(scene, ref: int, params="dense"):
    """SGM on view ``ref``'s rectified pair → disparity (H, W) float32 px (NaN holes), mask (H, W) bool."""
    disp_left, consistent = _left_right(scene, ref, params)
    disparity = np.where(consistent, disp_left, np.nan).astype(np.float32)
    return disparity, np.isfinite(disparity)


def sgm_left_right_failures(scene, ref: int, params="dense") -> np.ndarray:
    """(H, W) bool: pixels of view ``ref`` where SGBM answered but the left-right check failed, mostly
    points the right view does not see (occlusions) and a few mismatches."""
    disp_left, consistent = _left_right(scene, ref, params)
    return np.isfinite(disp_left) & ~consistent


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


def sgm_depth_subsampled(scene, ref: int, scale: int, params="dense") -> np.ndarray:
    """SGM depth of view ``ref`` of a scene rendered (or resampled) at ``scale``× the working size →
    (H, W) float32 metres at the working size, NaN holes: the centre pixel of each ``scale × scale``
    block (``scale`` odd). With K scaled as ``Camera.resized`` does, that pixel's ray is exactly the
    small pixel's ray, so the kept depth belongs to the small image's geometry."""
    if isinstance(scale, bool) or int(scale) != scale or scale < 1 or scale % 2 == 0:
        raise ValueError(f"scale must be an odd positive integer (so a pixel has a centre sample), got {scale!r}")
    scale = int(scale)
    depth, _ = sgm_depth(scene, ref, params=params)
    return depth[scale // 2::scale, scale // 2::scale].astype(np.float32)  # a contiguous copy


def gt_disparity(scene, ref: int) -> np.ndarray:
    """Ground-truth disparity of view ``ref`` (H, W) float32 px: f·B / depth − doffs (for KITTI's D1)."""
    view, _, baseline = _stereo_pair(scene, ref)
    return pixel_disparity(view.depth, view.camera.K[0, 0], baseline, scene.meta.get("doffs", 0.0))


def pixel_disparity(depth, focal: float, baseline: float, doffs: float = 0.0) -> np.ndarray:
    """Depth (H, W) metres → disparity (H, W) float32 px of the rectified pair: d = focal·baseline / Z − doffs;
    focal px, baseline m, doffs px (computed in float64; NaN stays NaN)."""
    return (float(focal) * float(baseline) / np.asarray(depth, dtype=np.float64) - float(doffs)).astype(np.float32)


def disparity_to_depth(disparity, focal: float, baseline: float, doffs: float = 0.0) -> np.ndarray:
    """Disparity (H, W) px → depth (H, W) float32 metres: Z = focal·baseline / (d + doffs); focal px,
    baseline m, doffs px. Non-finite disparities (Middlebury's ``inf``) and d + doffs ≤ 0 → NaN."""
    for name, value in (("focal", focal), ("baseline", baseline)):
        if not np.isfinite(value) or value <= 0:
            raise ValueError(f"{name} must be a positive finite number, got {value!r}")
    if not np.isfinite(doffs):
        raise ValueError(f"doffs must be finite, got {doffs!r}")
    d = np.asarray(disparity, dtype=np.float64)
    if d.ndim != 2:
        raise ValueError(f"disparity must be (H, W), got shape {d.shape}")
    denominator = d + float(doffs)
    valid = np.isfinite(denominator) & (denominator > 0)
    depth = np.full(d.shape, np.nan, dtype=np.float32)
    depth[valid] = (float(focal) * float(baseline) / denominator[valid]).astype(np.float32)
    return depth
