""":func:`complete_depth`, the entry point: one DDP fit, or the kit's combinations of fits a config asks for,
top to bottom:

    check the inputs once → hold out the valid pixels that choose a combination → fit (side by side
    where they may) → combine the fits → refine → mix in the fill's share

A config asks for at most four combinations: the mean of fits from other seeds (``ensemble``); the blend of
this config's fit with the paper recipe's (``blend_paper``), with the weight ``blend_weight`` or, for None,
the one that best predicts a ring of valid input held out of both fits; the result made sharp by an
image-guided edge-aware solve toward it (``refine``); a share of the input's colour-guided fill mixed in
(``blend_fill``), or, for None, the share that best predicts blobs of valid input held out of the fits. The
recipe ``photo`` is the kit's fit refined, with the kit's share of the fill. Each fit is one
:func:`ddp_lite.method.fit.run_fit` on the inputs checked once; each combination is built by
:mod:`ddp_lite.method.kit.combine`, its weights, shares and held-out pixels chosen by
:mod:`ddp_lite.method.kit.blend`.
"""
from __future__ import annotations

from dataclasses import replace

import numpy as np

from .kit.blend import best_fill_share, fill_held_out_mask
from .fit_cache import cached
from ..core.camera import Camera
from ..core.checks import MIN_VALID_PIXELS
from .config import FitConfig
from .paper.disparity import DisparityTransform
from .input_checks import FitInputs, check_fit_inputs
from .misplaced_arguments import names_misplaced_arguments
from .runtime.options import RunOptions
from .runtime.side_by_side import run_side_by_side, side_by_side_workers
from .fit import check_run, run_fit
from .kit.combine import combine_fits, fit_members, input_fill, mixed_with_fill, refined
from .result import DepthResult

__all__ = ["complete_depth", "fill_held_out", "without_held_out", "with_fill_share"]


@names_misplaced_arguments
@cached(like="depth", types=(DepthResult, DisparityTransform))
def complete_depth(rgb, depth, camera: Camera | None = None, neighbors=(), variant: str = "rgbd+warp",
                   config: FitConfig | None = None, gt_depth=None, transform: DisparityTransform | None = None,
                   callback=None, init: DepthResult | None = None, *, options: RunOptions | None = None
                   ) -> DepthResult:
    """Fill the holes (NaN) of ``depth`` (H, W, metres) with a Deep Depth Prior.

    Args:
        rgb: (H, W, 3) float in [0, 1], the reference image (unused by ``variant="d"``).
        depth: (H, W) float metres, NaN = hole.
        camera: the reference ``Camera`` (needed for the warp loss).
        neighbors: ``(rgb, Camera)`` pairs or ``View`` objects of calibrated neighbouring views.
        variant: ``"d"``, ``"rgbd"`` or ``"rgbd+warp"``.
        config: a :class:`FitConfig`; None → ``FitConfig.for_profile(variant=variant)``.
        gt_depth: (H, W) metres; when given, the hole error is tracked in ``history``.
        transform: depth ↔ disparity map; None → derived from the valid input depth.
        callback: ``callback(iteration, DepthResult-like dict)`` every ``options.callback_every``.
        init: a previous result (same variant and net) whose weights start this fit: a warm start
            for the next view of a sequence.
        options: how it runs, not what it computes: a :class:`RunOptions` (device, memory format and
            limit, progress bar, callback rate); None → ``RunOptions()``.
    Returns:
        :class:`DepthResult` with ``.depth`` (H, W) metres, ``.disparity``, ``.rgb``, ``.history``.

    Example:
        >>> depth = np.full((32, 32), 2.0, np.float32); depth[10:20, 10:20] = np.nan
        >>> cfg = FitConfig(channels=(8, 16), lr=1e-2, iterations=5)
        >>> complete_depth(np.zeros((32, 32, 3), np.float32), depth, variant="d", config=cfg,
        ...                options=RunOptions(progress=False)).depth.shape
        (32, 32)
    """
    options = check_run(options, callback, init)
    config = FitConfig.for_profile(variant=variant) if config is None else config
    inputs, config = check_fit_inputs(rgb, depth, camera, neighbors, variant, config, gt_depth, transform)
    target = inputs.transform.to_disparity(inputs.depth)  # (H, W), NaN holes: what held-out pixels are judged by
    # what the fits see: the input less the valid pixels held out to choose the fill's share and a blend's weight
    blobs = fill_held_out(inputs.depth, config)
    seen = without_held_out(inputs, blobs)
    members, ring = fit_members(seen.depth, config)
    fitted = without_held_out(seen, ring)
    # the fits, side by side where they may; a warm start fits the config's own net (a blend's second is the paper's)
    workers = side_by_side_workers(members[0], options, seen.spec, seen.depth.shape, len(seen.neighbors),
                                   len(members), callback)
    fits = run_side_by_side(lambda k: run_fit(fitted, members[k], options, callback=callback,
                                              init=init if k == 0 or not config.combination.blend_paper else None),
                            len(members), workers)
    result = combine_fits(fits, config, ring, target)
    if config.combination.refine:
        result = refined(result, seen.depth, seen.rgb, config.combination.depth_source)
    return with_fill_share(result, inputs, seen, config, blobs, target)


def fill_held_out(depth: np.ndarray, config: FitConfig) -> np.ndarray | None:
    """``blend_fill=None``: the valid pixels of ``depth`` (H, W) metres held out of the fits to choose the fill's
    share, blobs of :func:`~ddp_lite.method.kit.blend.fill_held_out_mask` (H, W) bool; None where the share is given,
    or where too little valid depth is left to hold any out (the share is then 0)."""
    if config.combination.blend_fill is not None:
        return None
    valid = np.isfinite(depth)
    held_out = fill_held_out_mask(valid, config.paper.seed)
    if held_out.sum() < MIN_VALID_PIXELS or (valid & ~held_out).sum() < MIN_VALID_PIXELS:
        return None
    return held_out


def without_held_out(inputs: FitInputs, held_out: np.ndarray | None) -> FitInputs:
    """``inputs`` with the ``held_out`` (H, W) bool pixels of their depth made holes; None: ``inputs`` as they are."""
    if held_out is None:
        return inputs
    return replace(inputs, depth=np.where(held_out, np.nan, inputs.depth).astype(np.float32))


def with_fill_share(result: DepthResult, inputs: FitInputs, seen: FitInputs, config: FitConfig,
                    held_out: np.ndarray | None, target: np.ndarray) -> DepthResult:
    """``result``, fitted on ``seen`` (``inputs`` less the ``held_out`` blobs of :func:`fill_held_out`), with
    ``config.combination.blend_fill`` f of the colour-guided fill of ``inputs`` mixed in
    (:func:`~ddp_lite.method.kit.combine.mixed_with_fill`; f = 0: ``result`` as it is). f = None: the share whose mix with a fill of ``seen`` best predicts ``target``
    (the input depth in normalised disparity, (H, W)) on the held-out blobs
    (:func:`~ddp_lite.method.kit.blend.best_fill_share`; ``history`` gets ``blend_fill_errors``, RMSE per share),
    or 0 where none were held out."""
    share, errors, source = config.combination.blend_fill, None, config.combination.depth_source
    if share == 0:
        return result
    if share is None and held_out is None:
        share = 0.0
    elif share is None:
        share, errors = best_fill_share(result.disparity, input_fill(seen.depth, seen.rgb, result.transform, source),
                                        target, held_out)
    mixed = mixed_with_fill(result, inputs.depth, inputs.rgb, share, source)
    if errors is not None:
        mixed.history["blend_fill_errors"] = errors
    return mixed


