""":func:`complete_depth`, the entry point: one DDP fit, or the kit's combinations of fits a config asks for,
top to bottom:

    check the inputs once → hold out the valid pixels that choose a combination → fit (side by side
    where they may) → combine the fits → refine → mix in the fill's share

A config asks for at most four combinations: the mean of fits from other seeds (``ensemble``); the blend of
this config's fit with the paper recipe's (``blend_paper``, :func:`blend_members`, :func:`blended_result`),
with the weight ``blend_weight`` or, for None, the one that best predicts a ring of valid input held out of
both fits; the result made sharp by an image-guided edge-aware solve toward it (``refine``, :func:`refined`);
a share of the input's colour-guided fill mixed in (``blend_fill``, :func:`mixed_with_fill`), or, for None,
the share that best predicts blobs of valid input held out of the fits. The recipe ``photo`` is the kit's fit
refined, with the kit's share of the fill. Each fit is one :func:`ddp_lite.method.fit.run_fit` on the inputs
checked once; the weights, shares and held-out pixels come from :mod:`ddp_lite.method.kit.blend`, the mean from
:mod:`ddp_lite.method.kit.ensemble`.
"""
from __future__ import annotations

from dataclasses import replace

import numpy as np

from .kit.blend import best_fill_share, best_weight, fill_disparity, fill_holdout, rim_width, trusted_depth, validation_ring
from .fit_cache import cached
from .full_resolution import SMOOTHNESS_MEAN, SMOOTHNESS_STEREO, refine_over_smoothness, smoothness_at
from ..core.camera import Camera
from ..core.checks import MIN_VALID_PIXELS
from .config import FitConfig
from .paper.disparity import DisparityTransform
from .kit.ensemble import mean_outputs
from .input_checks import FitInputs, check_fit_inputs
from .misplaced_arguments import names_misplaced_arguments
from .runtime.options import RunOptions
from .runtime.side_by_side import run_side_by_side, side_by_side_workers
from .fit import DepthResult, check_run, run_fit
from .kit.recipes import get_recipe

__all__ = ["complete_depth", "fill_heldout", "held_out", "with_fill_share", "blend_members", "blended_result",
           "combined_result", "refined", "input_fill", "mixed_with_fill", "SOLVE_SETTINGS"]


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
    inputs, config = check_fit_inputs(rgb, depth, camera, neighbors, variant, config, gt_depth, transform)
    target = inputs.transform.to_disparity(inputs.depth)  # (H, W), NaN holes: what held-out pixels are judged by
    # what the fits see: the input less the valid pixels held out to choose the fill's share and a blend's weight
    blobs = fill_heldout(inputs.depth, config)
    seen = held_out(inputs, blobs)
    members, ring = _fit_members(seen.depth, config)
    fitted = held_out(seen, ring)
    # the fits, side by side where they may; a warm start fits the config's own net (a blend's second is the paper's)
    workers = side_by_side_workers(members[0], options, seen.spec, seen.depth.shape, len(seen.neighbors),
                                   len(members), callback)
    fits = run_side_by_side(lambda k: run_fit(fitted, members[k], options, callback=callback,
                                              init=init if k == 0 or not config.combination.blend_paper else None),
                            len(members), workers)
    result = _combined(fits, config, ring, target)
    if config.combination.refine:
        result = refined(result, seen.depth, seen.rgb, config.combination.depth_source)
    return with_fill_share(result, inputs, seen, config, blobs, target)


def fill_heldout(depth: np.ndarray, config: FitConfig) -> np.ndarray | None:
    """``blend_fill=None``: the valid pixels of ``depth`` (H, W) metres held out of the fits to choose the fill's
    share, blobs of :func:`~ddp_lite.method.kit.blend.fill_holdout` (H, W) bool; None where the share is given,
    or where too little valid depth is left to hold any out (the share is then 0)."""
    if config.combination.blend_fill is not None:
        return None
    valid = np.isfinite(depth)
    heldout = fill_holdout(valid, config.paper.seed)
    if heldout.sum() < MIN_VALID_PIXELS or (valid & ~heldout).sum() < MIN_VALID_PIXELS:
        return None
    return heldout


def held_out(inputs: FitInputs, heldout: np.ndarray | None) -> FitInputs:
    """``inputs`` with the ``heldout`` (H, W) bool pixels of their depth made holes; None: ``inputs`` as they are."""
    if heldout is None:
        return inputs
    return replace(inputs, depth=np.where(heldout, np.nan, inputs.depth).astype(np.float32))


def _fit_members(depth: np.ndarray, config: FitConfig) -> tuple[list, np.ndarray | None]:
    """(the configs of the fits ``config`` asks for, one per fit; the ring held out of them, or None): the config
    itself; an ensemble's members, seeds seed, seed+1, ...; or a blend's two (:func:`blend_members`), with, for
    ``blend_weight=None``, the ring of valid ``depth`` (H, W) metres held out of both to choose the weight
    (:func:`~ddp_lite.method.kit.blend.validation_ring`); too little valid depth to judge by, or to fit
    without the ring: the config's own fit alone."""
    combination = config.combination
    if combination.blend_paper:
        members = list(blend_members(config))
        if combination.blend_weight is not None:
            return members, None
        valid = np.isfinite(depth)
        ring = validation_ring(valid, config.paper.seed)
        if (valid & ~ring).sum() < MIN_VALID_PIXELS or ring.sum() < MIN_VALID_PIXELS:
            return members[:1], None
        return members, ring
    return [config.replace(seed=config.paper.seed + k, ensemble=1) if combination.ensemble > 1 else config
            for k in range(combination.ensemble)], None


def _combined(fits: list, config: FitConfig, ring: np.ndarray | None, target: np.ndarray) -> DepthResult:
    """One result of the ``fits`` of :func:`_fit_members`: the one fit; an ensemble's mean (:func:`combined_result`);
    a blend's weighted sum (:func:`blended_result`), its weight ``blend_weight``, or the one that best predicts
    ``target`` (the input depth in normalised disparity, (H, W)) on the ``ring`` held out of both fits
    (``history`` gets ``blend_ring_errors``)."""
    if len(fits) == 1:
        return fits[0]
    combination, transform = config.combination, fits[0].transform
    if not combination.blend_paper:
        return combined_result(fits, transform, fits[0].history)
    weight, extra = combination.blend_weight, {}
    if ring is not None:
        weight, extra["blend_ring_errors"] = best_weight(fits[0].disparity, fits[1].disparity, target, ring)
    return blended_result(fits, transform, weight, extra)


def with_fill_share(result: DepthResult, inputs: FitInputs, seen: FitInputs, config: FitConfig,
                    heldout: np.ndarray | None, target: np.ndarray) -> DepthResult:
    """``result``, fitted on ``seen`` (``inputs`` less the ``heldout`` blobs of :func:`fill_heldout`), with
    ``config.combination.blend_fill`` f of the colour-guided fill of ``inputs`` mixed in (:func:`mixed_with_fill`;
    f = 0: ``result`` as it is). f = None: the share whose mix with a fill of ``seen`` best predicts ``target``
    (the input depth in normalised disparity, (H, W)) on the held-out blobs
    (:func:`~ddp_lite.method.kit.blend.best_fill_share`; ``history`` gets ``blend_fill_errors``, RMSE per share),
    or 0 where none were held out."""
    share, errors, source = config.combination.blend_fill, None, config.combination.depth_source
    if share == 0:
        return result
    if share is None and heldout is None:
        share = 0.0
    elif share is None:
        share, errors = best_fill_share(result.disparity, input_fill(seen.depth, seen.rgb, result.transform, source),
                                        target, heldout)
    mixed = mixed_with_fill(result, inputs.depth, inputs.rgb, share, source)
    if errors is not None:
        mixed.history["blend_fill_errors"] = errors
    return mixed


SOLVE_SETTINGS = {"clean": SMOOTHNESS_MEAN, "stereo": SMOOTHNESS_STEREO}  # depth_source → the solves refined averages


def refined(result: DepthResult, depth: np.ndarray, rgb: np.ndarray, source: str = "clean") -> DepthResult:
    """``config.combination.refine``: ``result`` made sharp at its own size, its depth the target of the
    image-guided edge-aware solve of :func:`~ddp_lite.method.full_resolution.refine_full_resolution` (the
    fast bilateral solver: confidence 1 on the valid input ``depth`` (H, W) metres, NaN holes, and 0.01 on
    the fit in the holes, after the fit's own error on the valid pixels is carried into them), guided by
    ``rgb`` (H, W, 3) in [0, 1], averaged over four smoothness settings (``refine_over_smoothness``;
    ``SOLVE_SETTINGS[source]``, their reach scaled to ``depth``'s size: ``full_resolution.smoothness_at``). A
    ``"stereo"`` ``source``'s rim is not read (``kit.blend.rim_width``, for ``depth``'s size).
    The fit is first clipped to the valid input's depth range: a fit can run off to the end of its
    disparity range inside a hole while it matches every valid pixel (one rgbd fit of 83 on the real suite),
    and the solve would keep that. The valid input comes back as given; ``history`` gets ``refined``.
    A fit blurs depth edges a few pixels wide; the solve puts them on the image's colour edges."""
    transform = result.transform
    target = np.clip(result.depth, np.nanmin(depth), np.nanmax(depth))  # (H, W) metres
    sharp = refine_over_smoothness(depth, rgb, target, smoothness_at(SOLVE_SETTINGS[source], depth.shape),
                                   rim=rim_width(source, shape=depth.shape))  # (H, W) metres
    disparity = np.asarray(transform.to_disparity(sharp), np.float32)
    return replace(result, disparity=disparity, depth=transform.to_depth(disparity).astype(np.float32),
                   history={**result.history, "refined": True})


def combined_result(members: list, transform, history: dict, weights=None) -> DepthResult:
    """One result from several fits: their (weighted) mean outputs; totals of iterations and seconds;
    the first fit's best iteration and weights."""
    disparity, rgb = mean_outputs(members, weights)
    return DepthResult(depth=transform.to_depth(disparity).astype(np.float32), disparity=disparity, rgb=rgb,
                       history=history, transform=transform, iterations=sum(m.iterations for m in members),
                       best_iteration=members[0].best_iteration, seconds=sum(m.seconds for m in members),
                       state=members[0].state, fits=len(members))


def blended_result(fits: list, transform, weight: float, history: dict | None = None) -> DepthResult:
    """The two fits of :func:`blend_members` as one result, weight·Z_own + (1 − weight)·Z_paper; ``history``
    is the first fit's, plus ``history`` and ``blend_weight``."""
    return combined_result(fits, transform, {**fits[0].history, **(history or {}), "blend_weight": weight},
                           weights=(weight, 1.0 - weight))


def blend_members(config: FitConfig) -> tuple[FitConfig, FitConfig]:
    """The two fits ``config.combination.blend_paper`` blends: this config's own fit and the paper recipe's,
    at the same size, budget and seed. Its ``blend_fill`` is left to the caller (it mixes into the blend)."""
    own = config.replace(blend_paper=False)
    return own, own.replace(**get_recipe("paper").overrides)


def input_fill(depth: np.ndarray, rgb: np.ndarray, transform, source: str = "clean") -> np.ndarray:
    """(H, W) float32: the colour-guided fill of the input ``depth`` (H, W) metres (NaN holes) that the kit
    mixes in, in ``transform``'s normalised disparity (:func:`ddp_lite.method.kit.blend.fill_disparity`),
    read without a ``"stereo"`` ``source``'s rim (``kit.blend.trusted_depth``); the valid input as given."""
    fill = fill_disparity(trusted_depth(depth, source), rgb, transform)
    if source == "clean":
        return fill
    return np.where(np.isfinite(depth), np.asarray(transform.to_disparity(depth), np.float32), fill)


def mixed_with_fill(result: DepthResult, depth: np.ndarray, rgb: np.ndarray, share: float,
                    source: str = "clean") -> DepthResult:
    """``result`` with ``share`` of the colour-guided fill of the input ``depth`` (H, W) metres (NaN holes),
    guided by ``rgb`` (H, W, 3), mixed into its disparity: (1 − share)·Z + share·Z_fill, in the result's
    transform (:func:`input_fill`, which reads a ``source``'s depth as ``refined`` does). ``history`` gets
    ``blend_fill``."""
    transform = result.transform
    disparity = result.disparity
    if share > 0:  # (share 0 leaves the fit's output as it is, bit for bit)
        disparity = ((1.0 - share) * disparity + share * input_fill(depth, rgb, transform, source)).astype(np.float32)
    return replace(result, disparity=disparity, depth=transform.to_depth(disparity).astype(np.float32),
                   history={**result.history, "blend_fill": share})
