"""Coarse-to-fine DDP: a first stage at 1/scale size, then the full size from its weights.

A speed-up (``benchmarks/bench_time_to_quality.py``), not part of the paper: the UNet is fully
convolutional, so weights fitted on a shrunk scene start the full-size fit.
"""
from __future__ import annotations

import dataclasses

import numpy as np
import torch

from ..core.camera import Camera
from .config import FitConfig
from .paper.disparity import DisparityTransform
from .complete import fill_held_out, without_held_out, with_fill_share
from .fit import check_run, fit_once, run_fit
from .input_checks import check_fit_inputs
from .kit.combine import refined
from .paper.nets import make_input
from .misplaced_arguments import names_misplaced_arguments
from .result import DepthResult
from .runtime.options import RunOptions

__all__ = ["complete_depth_coarse_to_fine"]


def _pad_to_multiple(array: np.ndarray, scale: int, mode: str) -> np.ndarray:
    """Pad (H, W[, C]) at the bottom and right to multiples of ``scale``: NaN (``"nan"``) or edge copies."""
    pad_h, pad_w = (-array.shape[0]) % scale, (-array.shape[1]) % scale
    if not (pad_h or pad_w):
        return array
    widths = ((0, pad_h), (0, pad_w)) + ((0, 0),) * (array.ndim - 2)
    return np.pad(array, widths, mode="constant", constant_values=np.nan) if mode == "nan" else np.pad(array, widths, mode="edge")


def _downsample_depth(depth: np.ndarray, scale: int) -> np.ndarray:
    """(H, W) metres with NaN holes → (⌈H/scale⌉, ⌈W/scale⌉): each ``scale × scale`` block becomes the
    nearest surface in it (min-pooling, no averaging across depth edges), or a hole (NaN) if any
    of its pixels is one: holes stay holes, and no coarse depth is made of partly unknown blocks."""
    padded = _pad_to_multiple(np.asarray(depth, np.float32), scale, "nan")
    h, w = padded.shape[0] // scale, padded.shape[1] // scale
    blocks = padded.reshape(h, scale, w, scale).transpose(0, 2, 1, 3).reshape(h, w, scale * scale)
    out = np.full((h, w), np.nan, np.float32)
    full = np.isfinite(blocks).all(axis=-1)
    out[full] = blocks[full].min(axis=-1)
    return out


def _downsample_image(image: np.ndarray, scale: int) -> np.ndarray:
    """(H, W, C) → (⌈H/scale⌉, ⌈W/scale⌉, C) by area averaging (edge-padded to a multiple of ``scale``)."""
    padded = _pad_to_multiple(np.asarray(image, np.float32), scale, "edge")
    h, w = padded.shape[0] // scale, padded.shape[1] // scale
    return padded.reshape(h, scale, w, scale, -1).mean(axis=(1, 3)).astype(np.float32)


def _downsample_camera(camera: Camera, scale: int) -> Camera:
    """The camera of an image padded (bottom/right) to multiples of ``scale`` and shrunk by ``scale``."""
    height, width = -(-camera.height // scale) * scale, -(-camera.width // scale) * scale
    return Camera(camera.K, camera.cam_from_world, width, height).resized(width // scale, height // scale)


@names_misplaced_arguments
def complete_depth_coarse_to_fine(rgb, depth, camera: Camera | None = None, neighbors=(), variant: str = "rgbd+warp",
                                  config: FitConfig | None = None, gt_depth=None,
                                  transform: DisparityTransform | None = None, coarse_fraction: float = 0.5,
                                  scale: int = 2, *, options: RunOptions | None = None) -> DepthResult:
    """:func:`~ddp_lite.method.complete.complete_depth` in two stages: first at 1/``scale`` size, then at full
    size from the coarse weights.

    The coarse stage runs ``round(coarse_fraction · iterations)`` iterations (no auto-stop) on the
    inputs shrunk by ``scale``: images by area averaging, depth (and ``gt_depth``) by min-pooling
    where a block holding any hole stays a hole, cameras via :meth:`Camera.resized` (images are
    padded bottom/right to a multiple of ``scale`` first). The UNet is fully convolutional, so
    its weights carry over; the full-size stage sees the coarse noise upsampled bilinearly, the
    same input at twice the resolution. It runs the remaining iterations with ``config`` as
    given (auto-stop included); the learning-rate schedule continues across the two stages.
    It is one fit: ``config.combination``'s ``ensemble`` and ``blend_paper`` do not apply; its ``refine`` and
    ``blend_fill`` do, to the full-size result (None: both stages fit without the held-out blobs that choose the share,
    as in :func:`complete_depth`: :func:`~ddp_lite.method.complete.fill_held_out`).

    Args:
        rgb: (H, W, 3) float in [0, 1] (may be None for ``variant="d"``).
        depth: (H, W) float metres, NaN = hole.
        camera, neighbors, variant, config, gt_depth, transform: as in :func:`complete_depth`.
        coarse_fraction: share of the iterations spent at the coarse size, in (0, 1).
        scale: integer shrink factor of the coarse stage, ≥ 2.
        options: how both stages run (:class:`RunOptions`), as in :func:`complete_depth`.

    Returns:
        :class:`DepthResult` of the full-size stage, ``.depth`` (H, W) metres. ``history`` joins
        both stages (full-size iterations offset by the coarse count; coarse hole errors are on
        the coarse grid) and adds ``eval_scale`` (scale of each evaluation), ``stage_iterations``
        and ``stage_seconds``; ``seconds`` and ``iterations`` are the totals.

    Example:
        >>> depth = np.full((32, 32), 2.0, np.float32); depth[10:20, 10:20] = np.nan
        >>> cfg = FitConfig(channels=(8, 16), lr=1e-2, iterations=6)
        >>> complete_depth_coarse_to_fine(None, depth, variant="d", config=cfg, options=RunOptions(progress=False)).depth.shape
        (32, 32)
    """
    if isinstance(scale, bool) or not isinstance(scale, (int, np.integer)) or scale < 2:
        raise ValueError(f"scale must be an integer ≥ 2, got {scale!r}")
    if not 0.0 < float(coarse_fraction) < 1.0:
        raise ValueError(f"coarse_fraction must lie in (0, 1), got {coarse_fraction!r}")
    options = check_run(options)
    config = FitConfig.for_profile(variant=variant) if config is None else config
    inputs, config = check_fit_inputs(rgb, depth, camera, neighbors, variant, config, gt_depth, transform)
    blobs = fill_held_out(inputs.depth, config)  # held out of both stages to choose the fill's share
    seen = without_held_out(inputs, blobs)
    rgb, depth, camera, neighbors, gt_depth = seen.rgb, seen.depth, seen.camera, seen.neighbors, seen.gt_depth
    scale = int(scale)
    H, W = depth.shape
    iterations = config.resolved_iterations(variant)
    n_coarse = min(max(int(round(coarse_fraction * iterations)), 1), iterations - 1)
    if n_coarse < 1:
        raise ValueError(f"config runs {iterations} iteration(s); coarse-to-fine needs at least 2")

    # the coarse stage: shrunk inputs, the first n_coarse iterations of the schedule, no auto-stop
    small = _downsample_depth(depth, scale)
    h, w = small.shape
    coarse_config = config.replace(iterations=n_coarse, auto_stop=False,
                                   lr_milestones=tuple(m for m in config.paper.lr_milestones if m < n_coarse))
    coarse_noise = make_input(config.net_inputs.base, config.paper.noise_channels, h, w, seed=config.paper.seed)
    coarse = fit_once(
        _downsample_image(rgb, scale) if rgb is not None else None, small,
        _downsample_camera(camera, scale) if camera is not None else None,
        [(_downsample_image(img, scale), _downsample_camera(cam, scale)) for img, cam in neighbors], variant,
        coarse_config, options=options, gt_depth=_downsample_depth(gt_depth, scale) if gt_depth is not None else None,
        transform=seen.transform, noise=coarse_noise)

    # the full-size stage: coarse weights, the same noise upsampled, the rest of the schedule
    passed = sum(1 for m in config.paper.lr_milestones if m <= n_coarse)
    fine_config = config.replace(iterations=iterations - n_coarse, lr=config.paper.lr * config.paper.lr_gamma ** passed,
                                 lr_milestones=tuple(m - n_coarse for m in config.paper.lr_milestones if m > n_coarse))
    fine_noise = torch.nn.functional.interpolate(coarse_noise, size=(h * scale, w * scale), mode="bilinear",
                                                 align_corners=False)[..., :H, :W].contiguous()
    fine = run_fit(seen, fine_config, options, init=coarse, noise=fine_noise)

    history = {}
    for key in fine.history:
        a, b = coarse.history.get(key), fine.history[key]
        if key in ("eval_iteration", "lr_decay_iteration"):
            history[key] = np.concatenate([a, b + coarse.iterations])
        elif a is not None:
            history[key] = np.concatenate([a, b])
    history["eval_scale"] = np.concatenate([np.full(len(coarse.history["eval_iteration"]), scale),
                                            np.ones(len(fine.history["eval_iteration"]), int)])
    history["stage_iterations"] = np.array([coarse.iterations, fine.iterations])
    history["stage_seconds"] = np.array([coarse.seconds, fine.seconds])
    result = dataclasses.replace(fine, history=history, iterations=coarse.iterations + fine.iterations,
                                 best_iteration=coarse.iterations + fine.best_iteration,
                                 seconds=coarse.seconds + fine.seconds)
    if config.combination.refine:
        result = refined(result, depth, rgb, config.combination.depth_source)
    target = inputs.transform.to_disparity(inputs.depth)  # (H, W), NaN holes: what the held-out blobs are judged by
    return with_fill_share(result, inputs, seen, config, blobs, target)
