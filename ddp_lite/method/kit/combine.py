"""The kit's combinations of whole fits, each a result built from fits :func:`~ddp_lite.method.fit.run_fit`
made (:mod:`ddp_lite.method.complete` runs the fits and calls these in its order):

- the fits a config asks for (:func:`fit_members`): its own; an ensemble's, seeds seed, seed+1, ...; or a
  blend's two, this config's fit and the paper recipe's (:func:`blend_members`);
- one result of them (:func:`combine_fits`): an ensemble's mean (:func:`combined_result`) or a blend's
  weighted sum (:func:`blended_result`);
- that result made sharp by an image-guided edge-aware solve toward it (:func:`refined`);
- a share of the input's colour-guided fill mixed in (:func:`input_fill`, :func:`mixed_with_fill`).

The weights, shares and held-out pixels that choose them come from :mod:`ddp_lite.method.kit.blend`, the
mean from :mod:`ddp_lite.method.kit.ensemble`, the solve from :mod:`ddp_lite.classical.full_resolution`.
A ``config`` here is a :class:`~ddp_lite.method.config.FitConfig`.
"""
from __future__ import annotations

from dataclasses import replace

import numpy as np

from ...classical.full_resolution import SMOOTHNESS_MEAN, SMOOTHNESS_STEREO, refine_over_smoothness, smoothness_at
from ...core.checks import MIN_VALID_PIXELS
from ..result import DepthResult
from .blend import best_weight, fill_disparity, rim_width, trusted_depth, validation_ring
from .ensemble import mean_outputs
from .recipes import get_recipe

__all__ = ["fit_members", "combine_fits", "SOLVE_SETTINGS", "refined", "combined_result", "blended_result",
           "blend_members", "input_fill", "mixed_with_fill"]


def fit_members(depth: np.ndarray, config) -> tuple[list, np.ndarray | None]:
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


def combine_fits(fits: list, config, ring: np.ndarray | None, target: np.ndarray) -> DepthResult:
    """One result of the ``fits`` of :func:`fit_members`: the one fit; an ensemble's mean (:func:`combined_result`);
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


SOLVE_SETTINGS = {"clean": SMOOTHNESS_MEAN, "stereo": SMOOTHNESS_STEREO}  # depth_source → the solves refined averages


def refined(result: DepthResult, depth: np.ndarray, rgb: np.ndarray, source: str = "clean") -> DepthResult:
    """``config.combination.refine``: ``result`` made sharp at its own size, its depth the target of the
    image-guided edge-aware solve of :func:`~ddp_lite.classical.full_resolution.refine_full_resolution` (the
    fast bilateral solver: confidence 1 on the valid input ``depth`` (H, W) metres, NaN holes, and 0.01 on
    the fit in the holes, after the fit's own error on the valid pixels is carried into them), guided by
    ``rgb`` (H, W, 3) in [0, 1], averaged over four smoothness settings (``refine_over_smoothness``;
    ``SOLVE_SETTINGS[source]``, their reach scaled to ``depth``'s size: ``full_resolution.smoothness_at``). A
    ``"stereo"`` ``source``'s rim is not read (``kit.blend.rim_width``, for ``depth``'s size).
    The fit is first clipped to the valid input's depth range: a fit can run off to the end of its
    disparity range inside a hole while it matches every valid pixel (seen on the real suite:
    ``docs/studies/real_suite.md``), and the solve would keep that. The valid input comes back as given;
    ``history`` gets ``refined``.
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


def blend_members(config) -> tuple:
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
