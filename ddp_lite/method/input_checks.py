"""What a depth fit is given, checked before any work: the config, depth, colour, camera,
neighbours, ground truth and transform (:func:`check_fit_inputs`).

A clear ``TypeError``/``ValueError`` naming the argument, or a warning for a neighbour that adds
nothing; nothing given is modified.
"""
from __future__ import annotations

import warnings

import numpy as np
import torch

from ..core.camera import Camera, view_overlap, view_parallax
from ..core.checks import check_depth, check_image
from .config import FitConfig
from .paper.disparity import DisparityTransform
from .paper.nets import check_input_size
from .paper.variants import get_variant
from ..core.views import image_and_camera

__all__ = ["check_fit_inputs", "MIN_PARALLAX_PX"]  # a Camera checks its own K (core.camera.check_intrinsics)


def _check_neighbors(neighbors) -> list[tuple[np.ndarray, Camera]]:
    if neighbors is None:  # "no neighbours", as the empty default
        return []
    if isinstance(neighbors, (np.ndarray, torch.Tensor, str)) or hasattr(neighbors, "camera"):
        raise TypeError(f"neighbors must be a list of (rgb, Camera) pairs or Views, got one "
                        f"{type(neighbors).__name__}; wrap a single view in a list")
    checked = []
    for i, item in enumerate(neighbors):
        checked.append(image_and_camera(item, f"neighbors[{i}]"))
    return checked


def _check_overlap(camera: Camera, depth: np.ndarray, neighbors) -> None:
    """Warn about each neighbour that sees none of the reference's valid depth; refuse if none does."""
    overlaps = [view_overlap(camera, depth, cam) for _, cam in neighbors]
    blind = [i for i, share in enumerate(overlaps) if share == 0.0]
    if len(blind) == len(neighbors):
        raise ValueError(f"neighbors: none of the {len(neighbors)} neighbour camera(s) sees any valid reference "
                         f"pixel (check their poses: cam_from_world, metres), so the warp term would be 0")
    for i in blind:
        warnings.warn(f"neighbors[{i}] sees none of the reference's valid pixels; its warp term is 0", stacklevel=4)


MIN_PARALLAX_PX = 0.5  # below this a neighbour's warp cannot tell one depth from another


def _check_useful_neighbors(camera: Camera, depth: np.ndarray, neighbors) -> None:
    """Refuse a neighbour that repeats another or sits at the reference's own pose (it adds nothing but
    weight); warn about one whose parallax over the valid depth is below ``MIN_PARALLAX_PX``."""
    for i, (image, cam) in enumerate(neighbors):
        if np.allclose(cam.cam_from_world, camera.cam_from_world, rtol=0.0, atol=1e-12):
            raise ValueError(f"neighbors[{i}] has the reference's own pose (zero baseline): its warp compares the "
                             f"reference with itself and adds nothing; use another view")
        for j in range(i):
            other_image, other = neighbors[j]
            if (np.array_equal(other.cam_from_world, cam.cam_from_world) and np.array_equal(other.K, cam.K)
                    and np.array_equal(other_image, image)):
                raise ValueError(f"neighbors[{i}] repeats neighbors[{j}] (same image and camera): it only doubles "
                                 f"that view's weight; list each neighbour once")
        parallax = view_parallax(camera, depth, cam)
        if parallax < MIN_PARALLAX_PX:
            baseline = float(np.linalg.norm(cam.center - camera.center))
            warnings.warn(f"neighbors[{i}]: a baseline of {baseline:.3g} (pose units) gives at most {parallax:.2g} px "
                          f"of parallax over the valid depth ({np.nanmin(depth):.3g}–{np.nanmax(depth):.3g} m), so its "
                          f"warp cannot tell depths apart; are depth and poses in the same unit (metres)?", stacklevel=4)


def _check_transform(transform: DisparityTransform, depth: np.ndarray) -> None:
    """Refuse a transform that does not cover the bulk of the valid depth (its 0.5–99.5th percentiles,
    the range ``DisparityTransform.from_depth`` covers before its margin): the fit could not
    reproduce those pixels, and every one of them would come back clipped."""
    lo, hi = np.percentile(depth[np.isfinite(depth)], [0.5, 99.5])
    if lo < transform.d_min or hi > transform.d_max:
        outside = int(((depth < transform.d_min) | (depth > transform.d_max)).sum())
        raise ValueError(f"transform: [{transform.d_min:.4g}, {transform.d_max:.4g}] m does not cover the valid "
                         f"depth (0.5–99.5th percentiles {lo:.4g}–{hi:.4g} m; {outside} pixel(s) outside would come "
                         f"back clipped); widen it, or pass transform=None to derive it from the depth")


def check_fit_inputs(rgb, depth, camera, neighbors, variant, config, gt_depth, transform):
    """Validate a depth fit's inputs before any work: (config, depth, rgb, neighbors, gt_depth, transform),
    the checked and converted values (``transform`` derived from the valid depth when None)."""
    spec = get_variant(variant)
    config = FitConfig.for_profile(variant=variant) if config is None else config
    if not isinstance(config, FitConfig):
        raise TypeError(f"config must be a FitConfig, got {type(config).__name__}")
    config.validate()
    depth = check_depth(depth)
    H, W = depth.shape
    check_input_size(config.paper.net, config.paper.channels, H, W)
    rgb = check_image(rgb, "rgb", (H, W)) if spec.uses_rgb or rgb is not None else None
    if config.combination.blend_fill != 0 and rgb is None:  # the fill is guided by the colour image (None: chosen)
        raise ValueError("config.blend_fill needs the colour image: pass rgb (H, W, 3), or set blend_fill=0")
    if config.combination.refine and rgb is None:  # the solve is guided by the colour image
        raise ValueError("config.refine needs the colour image: pass rgb (H, W, 3), or set refine=False")
    neighbors = _check_neighbors(neighbors)
    if camera is not None and not isinstance(camera, Camera):
        raise TypeError(f"camera must be a ddp_lite.Camera, got {type(camera).__name__}")
    if camera is not None and (camera.height, camera.width) != (H, W):
        raise ValueError(f"camera is {camera.height}×{camera.width} but depth is {H}×{W} (H×W)")
    if spec.needs_neighbors and (camera is None or not neighbors):
        raise ValueError(f"variant {spec.name!r} needs camera and at least one neighbor; use 'rgbd' without them")
    if spec.needs_neighbors:
        _check_overlap(camera, depth, neighbors)
        _check_useful_neighbors(camera, depth, neighbors)
    if gt_depth is not None:  # the kit's convention: NaN = unknown (a 0 would be scored as truth)
        gt_depth = check_depth(gt_depth, "gt_depth", min_valid=0, shape=(H, W))
    if transform is None:
        transform = DisparityTransform.from_depth(depth, margin=config.paper.disparity_margin)
    if not isinstance(transform, DisparityTransform):
        raise TypeError(f"transform must be a DisparityTransform, got {type(transform).__name__}")
    _check_transform(transform, depth)
    return config, depth, rgb, neighbors, gt_depth, transform
