"""Metrics the paper reports: depth errors, KITTI's D1, PSNR, and Tanks and Temples' P/R/F.

Conventions: depth (H, W) metres with NaN holes; disparity (H, W) pixels with NaN holes;
images (H, W, 3) or (H, W) in [0, data_range]; masks bool, True = counted. A NumPy masked array's
masked entries are unknown (NaN), never scored. No function here changes its inputs.

- ``rmse``/``mae``/``hole_rmse``: plain errors over a mask (default: where the truth is finite),
  so "error in the holes" is ``hole_rmse(pred, gt, ~input_mask)`` (paper Table 1, Fig. 5).
- ``d1_error``: KITTI 2015's outlier rate (paper Table 5).
- ``psnr``: 20·log10(MAX / √MSE) (paper Fig. 8, NYU v2).
- ``point_cloud_prf``: Tanks and Temples' precision/recall/F-score at a distance τ (Table 3);
  ``cloud_scores`` the same in %.
- ``disparity_rmse``, ``edge_band``, ``texture_leakage``: the notebooks' errors in normalised
  disparity ×100 (the unit of the paper's Middlebury table), near depth edges (Fig. 3), and
  colour texture copied into flat depth (Fig. 4).
"""
from __future__ import annotations

import numpy as np
from scipy import ndimage

from ..method.paper.disparity import DisparityTransform
from .open3d_loader import import_open3d

__all__ = ["rmse", "mae", "hole_rmse", "d1_error", "psnr", "point_cloud_prf", "cloud_scores", "disparity_rmse",
           "edge_band", "texture_leakage", "texture_leakage_map"]


def _plain(value):
    """``value`` as it is, or a NumPy masked array as float64 with its masked entries NaN (unknown, as
    every NaN here): ``np.asarray`` alone would drop the mask and score whatever lies under it."""
    if np.ma.isMaskedArray(value) and np.issubdtype(value.dtype, np.number):
        return np.ma.filled(value.astype(np.float64), np.nan)
    return value


def _pair(pred, gt, names=("pred", "gt")) -> tuple[np.ndarray, np.ndarray]:
    """float64 views of two same-shape numeric arrays, or a ValueError naming the argument."""
    out = []
    for value, name in zip((pred, gt), names):
        array = np.asarray(_plain(value))
        if not (np.issubdtype(array.dtype, np.floating) or np.issubdtype(array.dtype, np.integer)):
            raise TypeError(f"{name} must be a numeric array, got dtype {array.dtype}")
        if array.ndim == 0 or array.size == 0:
            raise ValueError(f"{name} must be a non-empty array, got shape {array.shape}")
        out.append(array.astype(np.float64))  # a copy: callers' arrays stay untouched
    if out[0].shape != out[1].shape:
        raise ValueError(f"{names[0]} and {names[1]} must have the same shape, got {out[0].shape} and {out[1].shape}")
    return out[0], out[1]


def _mask(mask, default: np.ndarray, shape: tuple, name: str = "mask") -> np.ndarray:
    """A bool mask of ``shape`` (``default`` when None), or a ValueError naming ``name``."""
    if mask is None:
        return default
    array = np.asarray(mask)
    if array.dtype != bool:
        raise TypeError(f"{name} must be a bool array (True = counted), got dtype {array.dtype}")
    if array.shape != shape:
        raise ValueError(f"{name} must have shape {shape}, got {array.shape}")
    return array


def _masked_errors(pred, gt, mask, mask_name: str = "mask") -> np.ndarray:
    """pred - gt at the counted pixels (1-D), after checking the mask selects finite values."""
    pred, gt = _pair(pred, gt)
    mask = _mask(mask, np.isfinite(gt), gt.shape, mask_name)
    if not mask.any():
        raise ValueError(f"{mask_name} selects no pixel (nothing to average); "
                         "by default it is where gt is finite")
    for array, name in ((pred, "pred"), (gt, "gt")):
        bad = int((~np.isfinite(array[mask])).sum())
        if bad:
            raise ValueError(f"{name} must be finite where {mask_name} is True; {bad} pixels are NaN/inf "
                             f"(fill the holes first, or leave them out of {mask_name})")
    return pred[mask] - gt[mask]


def rmse(pred, gt, mask=None) -> float:
    """Root-mean-square error √mean((pred - gt)²) over ``mask`` (default: finite ``gt``), same units as gt.

    Shapes: ``pred``, ``gt`` and ``mask`` (bool) all the same, e.g. (H, W) depth in metres.

    Example:
        >>> rmse(np.array([[1.0, 2.0], [3.0, 4.0]]), np.array([[1.0, 2.0], [3.0, 6.0]]))
        1.0
    """
    errors = _masked_errors(pred, gt, mask)
    return float(np.sqrt(np.mean(errors ** 2)))


def mae(pred, gt, mask=None) -> float:
    """Mean absolute error mean|pred - gt| over ``mask`` (default: finite ``gt``), same units as gt.

    Example:
        >>> mae(np.array([1.0, 2.0, 5.0]), np.array([1.0, 3.0, 3.0]))
        1.0
    """
    errors = _masked_errors(pred, gt, mask)
    return float(np.mean(np.abs(errors)))


def hole_rmse(pred, gt, holes) -> float:
    """RMSE inside the holes: ``rmse(pred, gt, mask=holes)``; ``holes`` (H, W) bool, True = was a hole.

    Note the sense of ``holes`` is the opposite of an input's valid mask: pass ``~mask``.
    """
    if holes is None:
        raise ValueError("holes must be a bool (H, W) array, True where the input depth was missing")
    errors = _masked_errors(pred, gt, holes, mask_name="holes")
    return float(np.sqrt(np.mean(errors ** 2)))


def d1_error(disp_pred, disp_gt, fg_mask=None, abs_threshold: float = 3.0, rel_threshold: float = 0.05) -> dict:
    """KITTI 2015 D1 outlier fractions in [0, 1]: ``{'d1_all', 'd1_bg', 'd1_fg'}``.

    A pixel is *bad* when |pred - gt| > 3 px **and** |pred - gt| > 5 % of gt. Only pixels with a
    finite, positive ``disp_gt`` (H, W) px count. A NaN (or inf) in ``disp_pred`` counts as bad:
    a method that leaves a hole is wrong there. (KITTI's devkit instead fills missing
    predictions by background interpolation before scoring; we do not, so holes are penalised.)
    ``fg_mask`` (H, W) bool marks foreground (cars in KITTI); ``d1_bg`` is over the rest. Without
    it every pixel is background: ``d1_bg == d1_all`` and ``d1_fg`` is NaN; a set with no valid
    pixel also gives NaN. ``abs_threshold`` (px) and ``rel_threshold`` are KITTI's 3 px and 5 %;
    3 px is meant for 1242 px wide images: on smaller images scale it with the width
    (3 · W / 1242), or nothing is ever an outlier.

    Example:
        >>> d1_error(np.array([10.0, 13.5, 100.0]), np.array([10.0, 10.0, 96.0]))["d1_all"]
        0.3333333333333333
    """
    pred, gt = _pair(disp_pred, disp_gt, ("disp_pred", "disp_gt"))
    fg = _mask(fg_mask, np.zeros(gt.shape, bool), gt.shape, "fg_mask")
    valid = np.isfinite(gt) & (gt > 0)
    if not valid.any():
        raise ValueError("disp_gt has no valid pixel (finite and > 0); D1 is undefined")
    if not (abs_threshold >= 0 and rel_threshold >= 0):
        raise ValueError(f"abs_threshold and rel_threshold must be ≥ 0, got {abs_threshold!r}, {rel_threshold!r}")
    with np.errstate(invalid="ignore"):
        err = np.abs(pred - gt)
        bad = ~np.isfinite(pred) | ((err > abs_threshold) & (err > rel_threshold * gt))

    def fraction(region):
        count = int(region.sum())
        return float(bad[region].sum() / count) if count else float("nan")

    return {"d1_all": fraction(valid), "d1_bg": fraction(valid & ~fg), "d1_fg": fraction(valid & fg)}


DATA_RANGE_SLACK = 2.0  # psnr: values may overshoot data_range a little (a fit's output), not by this factor


def psnr(pred, target, data_range: float = 1.0, mask=None) -> float:
    """Peak signal-to-noise ratio 10·log10(data_range² / MSE) in dB; ``inf`` for identical inputs.

    ``pred``, ``target``: (H, W) or (H, W, C) with the same shape; ``mask`` (H, W) bool (shared by the
    channels) or the full shape; default: where ``target`` is finite. For depth, pass
    ``data_range = d_max - d_min`` of the scene.

    Example:
        >>> round(psnr(np.full((2, 2), 0.5), np.full((2, 2), 0.6)), 2)
        20.0
    """
    pred, target = _pair(pred, target, ("pred", "target"))
    if isinstance(data_range, bool) or not (np.isscalar(data_range) and np.isfinite(data_range) and data_range > 0):
        raise ValueError(f"data_range must be a positive number, got {data_range!r}")
    if mask is not None and target.ndim == 3 and np.shape(mask) == target.shape[:2]:
        mask = np.broadcast_to(np.asarray(mask)[..., None], target.shape)  # one mask for all channels
    errors = _masked_errors(pred, target, mask)
    counted = _mask(mask, np.isfinite(target), target.shape)
    for array, name in ((target, "target"), (pred, "pred")):  # 0–255 images scored with data_range 1, say
        values = array[counted]
        spread = float(values.max() - values.min())
        if spread > DATA_RANGE_SLACK * float(data_range):
            raise ValueError(f"{name} spans {values.min():.4g}–{values.max():.4g}, more than {DATA_RANGE_SLACK:g}× "
                             f"data_range={data_range:g}: PSNR would be meaningless. Images in 0–255 need "
                             f"data_range=255 (or divide them by 255); depth needs data_range = d_max − d_min")
    mse = float(np.mean(errors ** 2))
    if mse == 0.0:
        return float("inf")
    return float(10.0 * np.log10(float(data_range) ** 2 / mse))


def _points(cloud, name: str) -> np.ndarray:
    """(N, 3) float64 points from an array or an ``open3d.geometry.PointCloud``."""
    o3d = import_open3d()

    if isinstance(cloud, o3d.geometry.PointCloud):
        points = np.asarray(cloud.points, dtype=np.float64)
    else:
        points = np.asarray(cloud)
        if not (np.issubdtype(points.dtype, np.floating) or np.issubdtype(points.dtype, np.integer)):
            raise TypeError(f"{name} must be an (N, 3) array or open3d PointCloud, got {type(cloud).__name__}")
        points = points.astype(np.float64)
    if points.ndim != 2 or points.shape[1] != 3:
        raise ValueError(f"{name} must be (N, 3) points, got shape {points.shape}")
    if len(points) == 0:
        raise ValueError(f"{name} is empty; precision/recall need at least one point")
    if not np.all(np.isfinite(points)):
        raise ValueError(f"{name} must contain only finite coordinates")
    return points


def point_cloud_prf(pred_points, gt_points, tau: float) -> dict:
    """Tanks and Temples precision, recall and F-score at distance ``tau`` (metres): a dict of floats in [0, 1].

    precision = fraction of predicted points within ``tau`` of the nearest ground-truth point;
    recall = fraction of ground-truth points within ``tau`` of the nearest predicted point
    (strictly closer than ``tau``, as TnT's evaluation does); F = 2PR / (P + R), 0 when both are 0.
    Inputs: (N, 3) / (M, 3) arrays or ``open3d.geometry.PointCloud``. Distances come from Open3D's
    ``compute_point_cloud_distance`` (a KD-tree). TnT also crops to a bounding volume and
    down-samples both clouds to ``tau``-sized voxels first; do that yourself if you need it.

    Example:
        >>> point_cloud_prf(np.zeros((1, 3)), np.array([[0.0, 0, 0], [1.0, 0, 0]]), tau=0.5)["recall"]
        0.5
    """
    o3d = import_open3d()

    if not (np.isscalar(tau) and np.isfinite(tau) and tau > 0):
        raise ValueError(f"tau must be a positive distance in metres, got {tau!r}")
    pred = o3d.geometry.PointCloud(o3d.utility.Vector3dVector(_points(pred_points, "pred_points")))
    gt = o3d.geometry.PointCloud(o3d.utility.Vector3dVector(_points(gt_points, "gt_points")))
    d_pred = np.asarray(pred.compute_point_cloud_distance(gt))  # (N,) pred → nearest gt
    d_gt = np.asarray(gt.compute_point_cloud_distance(pred))  # (M,) gt → nearest pred
    precision, recall = float(np.mean(d_pred < tau)), float(np.mean(d_gt < tau))
    total = precision + recall
    fscore = 2.0 * precision * recall / total if total > 0 else 0.0
    return {"precision": precision, "recall": recall, "fscore": float(fscore)}


def cloud_scores(points, gt_points, tau: float) -> dict[str, float]:
    """Tanks-and-Temples precision, recall and F-score in % of a point cloud ((N, 3) world metres or
    an Open3D cloud) against ``gt_points`` at distance ``tau`` metres."""
    scores = point_cloud_prf(points, gt_points, tau)
    return {"P": 100 * scores["precision"], "R": 100 * scores["recall"], "F": 100 * scores["fscore"]}


# --------------------------------------------------------------------------- normalised disparity

def edge_band(depth, width: int = 3, relative_jump: float = 0.05) -> np.ndarray:
    """(H, W) bool: pixels within ``width`` px of a depth discontinuity (a jump > 5 % between
    4-neighbours) of a hole-free depth map (H, W) metres."""
    depth = np.asarray(depth, dtype=np.float64)
    jump = np.zeros(depth.shape, bool)
    dx = np.abs(np.diff(depth, axis=1)) > relative_jump * np.minimum(depth[:, 1:], depth[:, :-1])
    dy = np.abs(np.diff(depth, axis=0)) > relative_jump * np.minimum(depth[1:], depth[:-1])
    jump[:, 1:] |= dx
    jump[:, :-1] |= dx
    jump[1:] |= dy
    jump[:-1] |= dy
    return ndimage.binary_dilation(jump, iterations=max(int(width), 0)) if width else jump


def disparity_rmse(depth, gt, mask, transform: DisparityTransform) -> float:
    """RMSE ×100 of normalised disparity between two depth maps (H, W metres) on ``mask`` ((H, W) bool);
    NaN when no pixel of ``mask`` has both depths finite (an empty edge band, say)."""
    depth, gt = _pair(depth, gt, ("depth", "gt"))
    if mask is None:
        raise ValueError("mask must be an (H, W) bool array, True where the error is counted")
    mask = _mask(mask, None, gt.shape) & np.isfinite(depth) & np.isfinite(gt)
    if not mask.any():
        return float("nan")
    error = transform.to_disparity(depth) - transform.to_disparity(gt)
    return float(100.0 * np.sqrt(np.mean(error[mask] ** 2)))


def texture_leakage_map(depth, gt, transform: DisparityTransform, band: int = 3, region=None) -> np.ndarray:
    """|Laplacian| ×100 of the normalised disparity of ``depth`` (H, W metres), (H, W), on the pixels
    where the truth ``gt`` is locally planar (its own Laplacian ≈ 0) and away from depth edges;
    NaN elsewhere. :func:`texture_leakage` is its mean.

    For a plane, inverse depth is an affine function of the pixel coordinates, so its Laplacian is
    zero; with ``transform.constant == 0`` the same holds for normalised disparity. Colour texture
    copied into the depth (paper Fig. 4: wooden planks on a flat wall) shows up as a non-zero
    Laplacian exactly there. ``region`` (H, W) bool restricts the measure further (for example
    to the planks: ``case.labels == views.LABEL_PLANKS``).
    """
    kernel = np.array([[0.0, 1.0, 0.0], [1.0, -4.0, 1.0], [0.0, 1.0, 0.0]])
    depth, gt = _pair(depth, gt, ("depth", "gt"))
    if depth.ndim != 2:
        raise ValueError(f"depth and gt must be (H, W) metres, got shape {depth.shape}")
    out = ndimage.convolve(transform.to_disparity(depth), kernel, mode="nearest")
    truth = ndimage.convolve(transform.to_disparity(gt), kernel, mode="nearest")
    planar = (np.abs(truth) < 1e-4) & ~edge_band(gt, band)
    if region is not None:
        planar &= _mask(region, None, gt.shape, "region")
    planar = ndimage.binary_erosion(planar, iterations=1)
    return np.where(planar, 100.0 * np.abs(out), np.nan)


def texture_leakage(depth, gt, transform: DisparityTransform, band: int = 3, region=None) -> float:
    """Mean of :func:`texture_leakage_map` over the pixels it measures (NaN if none): how much
    colour texture leaked into the depth of planar surfaces."""
    leakage = texture_leakage_map(depth, gt, transform, band, region)
    return float(np.nanmean(leakage)) if np.isfinite(leakage).any() else float("nan")
