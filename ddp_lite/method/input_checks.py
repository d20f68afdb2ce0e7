"""What a depth fit is given, checked once before any work: the config, depth, colour, ground truth,
camera, neighbours and transform (:func:`check_fit_inputs`), into :class:`FitInputs`.

A clear ``TypeError``/``ValueError`` naming the argument, or a warning for a neighbour that adds
nothing (:func:`~ddp_lite.core.views.check_neighbor_views`) and for a setting that acts on nothing
(:mod:`~ddp_lite.method.inert_settings`); nothing given is modified.
"""
from __future__ import annotations

import warnings
from dataclasses import dataclass

import numpy as np
import torch

from ..core.camera import Camera
from ..core.checks import check_depth, check_image, check_same_units
from ..core.views import check_neighbor_views, image_and_camera
from .config import FitConfig
from .inert_settings import warn_inert_settings
from .paper.disparity import DisparityTransform
from .paper.nets import check_input_size
from .paper.variants import Variant, get_variant

__all__ = ["FitInputs", "check_fit_inputs"]  # a Camera checks its own K (core.camera.check_intrinsics)


@dataclass(frozen=True)
class FitInputs:
    """A fit's inputs as :func:`check_fit_inputs` leaves them: checked, converted, the variant resolved."""

    rgb: np.ndarray | None  # (H, W, 3) float32 in [0, 1]; None where the variant has no use for it
    depth: np.ndarray  # (H, W) float32 metres, NaN = hole
    camera: Camera | None
    neighbors: list  # (rgb, Camera) pairs
    spec: Variant
    gt_depth: np.ndarray | None  # (H, W) metres, NaN = unknown
    transform: DisparityTransform


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


def check_fit_inputs(rgb, depth, camera, neighbors, variant, config, gt_depth, transform
                     ) -> tuple[FitInputs, FitConfig]:
    """Validate a depth fit's inputs before any work: (:class:`FitInputs`, the config), the checked and
    converted values (``transform`` None → derived from the valid depth). ``config`` must be a
    :class:`FitConfig`: a check reads no environment, so an entry point that takes None builds the
    profile's (``FitConfig.for_profile``, which reads ``DDP_PROFILE`` and ``DDP_RECIPE``) before calling this."""
    spec = get_variant(variant)
    if not isinstance(config, FitConfig):
        raise TypeError(f"config must be a FitConfig, got {type(config).__name__}")
    config.validate()
    # the arrays, each against the depth's (H, W); then the net's smallest input
    depth = check_depth(depth)
    H, W = depth.shape
    rgb = check_image(rgb, "rgb", (H, W)) if spec.uses_rgb or rgb is not None else None
    if gt_depth is not None:  # the kit's convention: NaN = unknown (a 0 would be scored as truth)
        gt_depth = check_depth(gt_depth, "gt_depth", min_valid=1, shape=(H, W))  # all NaN: nothing to score
        check_same_units(depth, gt_depth, "depth", "gt_depth")  # centimetres against metres: a 100× error scored
        if not (np.isfinite(gt_depth) & ~np.isfinite(depth)).any():
            warnings.warn("gt_depth has no valid value in the holes of depth, so the hole error is not defined: "
                          "history's hole_rmse will be NaN", stacklevel=3)
    check_input_size(config.paper.net, config.paper.channels, H, W)
    if config.combination.blend_fill != 0 and rgb is None:  # the fill is guided by the colour image (None: chosen)
        raise ValueError("config.blend_fill needs the colour image: pass rgb (H, W, 3), or set blend_fill=0")
    if config.combination.refine and rgb is None:  # the solve is guided by the colour image
        raise ValueError("config.refine needs the colour image: pass rgb (H, W, 3), or set refine=False")
    # the views: the reference camera and the neighbours that the warp term compares it with
    neighbors = _check_neighbors(neighbors)
    if camera is not None and not isinstance(camera, Camera):
        raise TypeError(f"camera must be a ddp_lite.Camera, got {type(camera).__name__}")
    if camera is not None and (camera.height, camera.width) != (H, W):
        raise ValueError(f"camera is {camera.height}×{camera.width} but depth is {H}×{W} (H×W)")
    if spec.needs_neighbors and (camera is None or not neighbors):
        raise ValueError(f"variant {spec.name!r} needs camera and at least one neighbor; use 'rgbd' without them")
    if spec.needs_neighbors:
        check_neighbor_views(camera, depth, neighbors)
    warn_inert_settings(config, spec, len(neighbors), stacklevel=4)  # said before the fit, as the errors are
    # the depth ↔ disparity map: derived from the valid depth, or one given that must cover it
    if transform is None:
        transform = DisparityTransform.from_depth(depth, margin=config.paper.disparity_margin)
    elif not isinstance(transform, DisparityTransform):
        raise TypeError(f"transform must be a DisparityTransform, got {type(transform).__name__}")
    else:
        transform.check_covers(depth, "transform")
    return FitInputs(rgb, depth, camera, neighbors, spec, gt_depth, transform), config
