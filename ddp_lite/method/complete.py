""":func:`complete_depth`, the entry point: one DDP fit, or the kit's combinations of fits a config asks for.

A config asks for at most four, applied from the outside in: a share of the input's colour-guided
fill mixed into the result (``blend_fill``, :func:`with_fill`); the result made sharp by an image-guided
edge-aware solve toward it (``refine``, :func:`refined`); the blend of this config's fit with the paper
recipe's (``blend_paper``, :func:`fit_blended`); the mean of several fits from other seeds (``ensemble``,
:func:`fit_ensemble`). The recipe ``photo`` is the kit's fit refined, with the kit's share of the fill. Each member is
one fit of :func:`ddp_lite.method.fit.run_fit` on the inputs checked once; the weights and shares
come from :mod:`ddp_lite.method.kit.blend`, the members' scheduling from :mod:`ddp_lite.method.kit.ensemble`.
"""
from __future__ import annotations

from dataclasses import replace

import numpy as np

from .kit.blend import best_fill_share, best_weight, fill_disparity, fill_holdout, validation_ring
from .fit_cache import cached
from .full_resolution import refine_full_resolution
from ..core.camera import Camera
from ..core.checks import MIN_VALID_PIXELS
from .config import FitConfig
from .paper.disparity import DisparityTransform
from .kit.ensemble import mean_outputs, parallel_members
from .runtime.options import RunOptions
from .runtime.side_by_side import run_side_by_side
from .fit import DepthResult, FitInputs, check_inputs, run_fit
from .kit.recipes import get_recipe
from .paper.variants import get_variant

__all__ = ["complete_depth", "fit_ensemble", "fit_blended", "blend_members", "blended_result", "combined_result",
           "refined",
           "with_fill", "mixed_with_fill"]


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
    spec = get_variant(variant)  # a bad name fails here, before any config is built
    config = FitConfig.for_profile(variant=variant) if config is None else config
    inputs, config, options = check_inputs(rgb, depth, camera, neighbors, spec, config, gt_depth, transform, init,
                                           options, callback)
    if config.combination.blend_fill != 0:
        return with_fill(lambda held_out: _fits(replace(inputs, depth=held_out), config.replace(blend_fill=0.0),
                                                options, callback, init), inputs.depth, inputs.rgb, config)
    return _fits(inputs, config, options, callback, init)


def _fits(inputs: FitInputs, config: FitConfig, options, callback, init) -> DepthResult:
    """One fit, a blend or an ensemble, as ``config`` asks, refined when it asks (its ``blend_fill`` is the
    caller's)."""
    if config.combination.blend_paper:
        result = fit_blended(inputs, config, options, callback, init)
    elif config.combination.ensemble == 1:
        result = run_fit(inputs, config, options, callback=callback, init=init)
    else:
        result = fit_ensemble(inputs, config, options, callback, init)
    return refined(result, inputs.depth, inputs.rgb) if config.combination.refine else result


def refined(result: DepthResult, depth: np.ndarray, rgb: np.ndarray) -> DepthResult:
    """``config.combination.refine``: ``result`` made sharp at its own size, its depth the target of the
    image-guided edge-aware solve of :func:`~ddp_lite.method.full_resolution.refine_full_resolution` (the
    fast bilateral solver: confidence 1 on the valid input ``depth`` (H, W) metres, NaN holes, and 0.01 on
    the fit in the holes, after the fit's own error on the valid pixels is carried into them), guided by
    ``rgb`` (H, W, 3) in [0, 1]. The valid input comes back as given; ``history`` gets ``refined``.
    A fit blurs depth edges a few pixels wide; the solve puts them on the image's colour edges."""
    transform = result.transform
    sharp = refine_full_resolution(depth, rgb, result.depth)  # (H, W) metres
    disparity = np.asarray(transform.to_disparity(sharp), np.float32)
    return replace(result, disparity=disparity, depth=transform.to_depth(disparity).astype(np.float32),
                   history={**result.history, "refined": True})


def fit_ensemble(inputs: FitInputs, config: FitConfig, options, callback, init) -> DepthResult:
    """``config.combination.ensemble`` independent fits from other seeds (other weights, noise and held-out
    pixels), averaged in disparity: one fit's hole error moves ±10 % and more with the seed, the mean keeps what
    the fits agree on. ``history`` is the first fit's."""
    def fit_member(k: int) -> DepthResult:
        return run_fit(inputs, config.replace(seed=config.paper.seed + k, ensemble=1), options, callback=callback,
                       init=init)

    workers = parallel_members(config, options, inputs.spec, inputs.depth.shape, len(inputs.neighbors), callback)
    members = run_side_by_side(fit_member, int(config.combination.ensemble), workers)
    return combined_result(members, inputs.transform, members[0].history)


def combined_result(members: list, transform, history: dict, weights=None) -> DepthResult:
    """One result from several fits: their (weighted) mean outputs; totals of iterations and seconds;
    the first fit's best iteration and weights."""
    disparity, rgb = mean_outputs(members, weights)
    return DepthResult(depth=transform.to_depth(disparity).astype(np.float32), disparity=disparity, rgb=rgb,
                       history=history, transform=transform, iterations=sum(m.iterations for m in members),
                       best_iteration=members[0].best_iteration, seconds=sum(m.seconds for m in members),
                       state=members[0].state, fits=len(members))


def fit_blended(inputs: FitInputs, config: FitConfig, options, callback, init) -> DepthResult:
    """``config.combination.blend_paper``: this config's fit and the paper recipe's, blended with weight
    ``config.combination.blend_weight``, or (None) with the weight that best predicts a ring of valid input
    held out of both fits (:mod:`ddp_lite.method.kit.blend`). ``history`` is the first fit's plus ``blend_weight`` and,
    with the ring, ``blend_ring_errors``."""
    depth, transform = inputs.depth, inputs.transform
    weight, members = config.combination.blend_weight, blend_members(config)
    valid = np.isfinite(depth)
    ring = validation_ring(valid, members[0].paper.seed) if weight is None else np.zeros_like(valid)
    if weight is None and ((valid & ~ring).sum() < MIN_VALID_PIXELS or ring.sum() < MIN_VALID_PIXELS):
        return run_fit(inputs, members[0], options, callback=callback, init=init)  # too little to judge by (or fit without)
    held_out = replace(inputs, depth=np.where(ring, np.nan, depth).astype(np.float32)) if ring.any() else inputs

    def fit_member(k: int) -> DepthResult:  # a warm start fits the first fit's net only
        return run_fit(held_out, members[k], options, callback=callback, init=init if k == 0 else None)

    workers = parallel_members(members[0].replace(ensemble=2), options, inputs.spec, depth.shape, len(inputs.neighbors),
                               callback)
    fits = run_side_by_side(fit_member, 2, workers)
    extra = {}
    if weight is None:
        weight, extra["blend_ring_errors"] = best_weight(fits[0].disparity, fits[1].disparity,
                                                         transform.to_disparity(depth), ring)
    return blended_result(fits, transform, weight, extra)


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


def with_fill(fit, depth: np.ndarray, rgb: np.ndarray, config: FitConfig) -> DepthResult:
    """``fit(depth) -> DepthResult`` with ``config.combination.blend_fill`` f of the colour-guided fill of
    ``depth`` (H, W) metres (NaN holes) mixed in (:func:`mixed_with_fill`). f = None: ``fit`` runs on ``depth`` with
    blobs of its valid pixels held out (:func:`~ddp_lite.method.kit.blend.fill_holdout`), and f is the share
    that best predicts them against a fill of the same held-out input
    (:func:`~ddp_lite.method.kit.blend.best_fill_share`); ``history`` gets ``blend_fill_errors`` (RMSE per
    share, normalised disparity). Too little valid depth to hold any out: the fit alone (f = 0)."""
    share = config.combination.blend_fill
    if share is not None:
        return mixed_with_fill(fit(depth), depth, rgb, share)
    valid = np.isfinite(depth)
    heldout = fill_holdout(valid, config.paper.seed)
    if heldout.sum() < MIN_VALID_PIXELS or (valid & ~heldout).sum() < MIN_VALID_PIXELS:
        return mixed_with_fill(fit(depth), depth, rgb, 0.0)
    held_out = np.where(heldout, np.nan, depth).astype(np.float32)
    fitted = fit(held_out)
    transform = fitted.transform
    share, errors = best_fill_share(fitted.disparity, fill_disparity(held_out, rgb, transform),
                                    transform.to_disparity(depth), heldout)
    result = mixed_with_fill(fitted, depth, rgb, share)
    result.history["blend_fill_errors"] = errors
    return result


def mixed_with_fill(result: DepthResult, depth: np.ndarray, rgb: np.ndarray, share: float) -> DepthResult:
    """``result`` with ``share`` of the colour-guided fill of the input ``depth`` (H, W) metres (NaN holes),
    guided by ``rgb`` (H, W, 3), mixed into its disparity: (1 − share)·Z + share·Z_fill, in the result's
    transform (:func:`ddp_lite.method.kit.blend.fill_disparity`). ``history`` gets ``blend_fill``."""
    transform = result.transform
    disparity = result.disparity
    if share > 0:  # (share 0 leaves the fit's output as it is, bit for bit)
        disparity = ((1.0 - share) * disparity + share * fill_disparity(depth, rgb, transform)).astype(np.float32)
    return replace(result, disparity=disparity, depth=transform.to_depth(disparity).astype(np.float32),
                   history={**result.history, "blend_fill": share})
