"""Deep Depth Prior: fill the holes of one depth map by fitting a net from fixed noise (paper Sec. 3).

:func:`complete_depth` runs one of the three variants (:mod:`ddp_lite.method.variants`): ``"d"``
(disparity only), ``"rgbd"`` (disparity + colour) and ``"rgbd+warp"`` (plus photo-consistency with
calibrated neighbours). :func:`fit_once` prepares one fit and hands its loss to the loop
(:func:`ddp_lite.method.loop.run`): the paper's loss (:mod:`ddp_lite.method.paper_method`) plus, when the config
asks for them, the kit's hole terms (:mod:`ddp_lite.method.hole_terms`) and net inputs
(:mod:`ddp_lite.method.nets`); ``config.ensemble > 1`` averages several fits (:mod:`ddp_lite.method.ensemble`).

The fit's other pieces live beside this module: :class:`~ddp_lite.method.config.FitConfig`, the input
checks (:mod:`ddp_lite.method.fit_inputs`), :func:`~ddp_lite.method.dip.fit_image` (Deep Image Prior on images),
:func:`~ddp_lite.method.coarse_to_fine.complete_depth_coarse_to_fine` (built on this module's pieces).
"""
from __future__ import annotations

import time
from dataclasses import dataclass, field, replace

import numpy as np
import torch

from . import loop
from .cache import cached
from ..core.checks import MIN_VALID_PIXELS, check_callback, check_depth, unmask
from .config import FitConfig
from .device import resolve_device
from .disparity import DisparityTransform
from .blend import best_fill_share, best_weight, fill_disparity, fill_holdout, validation_ring
from .ensemble import mean_outputs, parallel_members, run_members
from .fit_inputs import check_fit_inputs
from .hole_terms import HoleTerms
from .loop import check_finite_output, check_memory, holdout_mask, to_tensor
from .nets import fill_channel, image_channels
from .paper_method import PaperLoss
from .recipes import get_recipe
from .variants import get_variant

__all__ = ["DepthResult", "complete_depth", "merge", "fit_once", "mixed_with_fill", "with_fill", "blend_members",
           "blended_result"]


@dataclass
class DepthResult:
    """What :func:`complete_depth` returns. Arrays are NumPy, (H, W) or (H, W, 3).

    For the mean of several fits (``config.ensemble > 1``, ``fits`` of them) ``iterations`` and
    ``seconds`` are totals over the fits; ``history``, ``best_iteration`` and ``state`` are the
    first fit's.
    """

    depth: np.ndarray  # metres, holes filled
    disparity: np.ndarray  # [0, 1], see ``transform``
    rgb: np.ndarray | None  # the net's colour output (None for depth only)
    history: dict  # per-iteration loss terms; per-evaluation held-out and hole errors; lr_decay_iteration
    transform: DisparityTransform
    iterations: int  # iterations run
    best_iteration: int  # the iteration whose output is returned
    seconds: float
    state: dict | None = field(default=None, repr=False)  # the net's final weights (CPU), for warm starts
    fits: int = 1  # how many fits' disparities were averaged (config.ensemble)

    def merged(self, input_depth) -> np.ndarray:
        """"SGM+DDP": the input where it is valid, this result in its holes."""
        return merge(input_depth, self.depth)


def merge(input_depth, ddp_depth) -> np.ndarray:
    """(H, W) metres: ``input_depth`` where it is finite, ``ddp_depth`` in its holes ("SGM+DDP").

    ``input_depth`` follows the kit's convention (NaN holes, a masked array's mask = holes); a 0 or
    negative "hole" marker, or inf, is refused rather than kept as a depth."""
    input_depth = check_depth(input_depth, "input_depth", min_valid=0)
    ddp_depth = np.asarray(unmask(ddp_depth, "ddp_depth", holes=True))
    if not (np.issubdtype(ddp_depth.dtype, np.floating) or np.issubdtype(ddp_depth.dtype, np.integer)):
        raise TypeError(f"ddp_depth must be an (H, W) array of metres, got dtype {ddp_depth.dtype}")
    ddp_depth = ddp_depth.astype(np.float32)
    if input_depth.shape != ddp_depth.shape:
        raise ValueError(f"input_depth {input_depth.shape} and ddp_depth {ddp_depth.shape} must have the same shape")
    return np.where(np.isfinite(input_depth), input_depth, ddp_depth).astype(np.float32)


# --------------------------------------------------------------------------- the fit

@cached(like="depth", types=(DepthResult, DisparityTransform))
def complete_depth(rgb, depth, camera: Camera | None = None, neighbors=(), variant: str = "rgbd+warp",
                   config: FitConfig | None = None, gt_depth=None, transform: DisparityTransform | None = None,
                   callback=None, init: DepthResult | None = None) -> DepthResult:
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
        callback: ``callback(iteration, DepthResult-like dict)`` every ``config.callback_every``.
        init: a previous result (same variant and net) whose weights start this fit: a warm start
            for the next view of a sequence.
    Returns:
        :class:`DepthResult` with ``.depth`` (H, W) metres, ``.disparity``, ``.rgb``, ``.history``.

    Example:
        >>> depth = np.full((32, 32), 2.0, np.float32); depth[10:20, 10:20] = np.nan
        >>> cfg = FitConfig(channels=(8, 16), lr=1e-2, iterations=5, progress=False)
        >>> complete_depth(np.zeros((32, 32, 3), np.float32), depth, variant="d", config=cfg).depth.shape
        (32, 32)
    """
    get_variant(variant)  # a bad name fails here, before any config is built
    config = FitConfig.for_profile(variant=variant) if config is None else config
    check_callback(callback, config.callback_every if isinstance(config, FitConfig) else None)
    if isinstance(config, FitConfig) and config.blend_fill != 0:
        return fit_with_fill(rgb, depth, camera, neighbors, variant, config, gt_depth, transform, callback, init)
    if isinstance(config, FitConfig) and config.blend_paper:
        return fit_blended(rgb, depth, camera, neighbors, variant, config, gt_depth, transform, callback, init)
    if not isinstance(config, FitConfig) or config.ensemble == 1:
        return fit_once(rgb, depth, camera, neighbors, variant, config, gt_depth=gt_depth, transform=transform,
                        callback=callback, init=init)
    # An ensemble: independent fits from other seeds (other weights, noise and held-out pixels),
    # averaged in disparity. One fit's hole error moves ±10 % and more with the seed; the average
    # keeps what the fits agree on. The inputs are checked once, before the first fit.
    # one transform for every member (the checks derive it from the input depth when None)
    config, _, _, neighbors, _, transform = check_fit_inputs(rgb, depth, camera, neighbors, variant, config,
                                                              gt_depth, transform)
    def fit_member(k: int) -> DepthResult:
        return fit_once(rgb, depth, camera, neighbors, variant, config.replace(seed=config.seed + k, ensemble=1),
                        gt_depth=gt_depth, transform=transform, callback=callback, init=init)

    workers = parallel_members(config, variant, depth.shape, len(neighbors), callback)
    members = run_members(fit_member, int(config.ensemble), workers)
    return combined_result(members, transform, members[0].history)


def combined_result(members: list, transform, history: dict, weights=None) -> DepthResult:
    """One result from several fits: their (weighted) mean outputs; totals of iterations and seconds;
    the first fit's best iteration and weights."""
    disparity, rgb = mean_outputs(members, weights)
    return DepthResult(depth=transform.to_depth(disparity).astype(np.float32), disparity=disparity, rgb=rgb,
                       history=history, transform=transform, iterations=sum(m.iterations for m in members),
                       best_iteration=members[0].best_iteration, seconds=sum(m.seconds for m in members),
                       state=members[0].state, fits=len(members))


def fit_blended(rgb, depth, camera, neighbors, variant, config, gt_depth, transform, callback, init) -> DepthResult:
    """``config.blend_paper``: this config's fit and the paper recipe's, blended with weight
    ``config.blend_weight``, or (None) with the weight that best predicts a ring of valid input held out
    of both fits (:mod:`ddp_lite.method.blend`). ``history`` is the first fit's plus ``blend_weight`` and,
    with the ring, ``blend_ring_errors``."""
    config, depth, _, neighbors, _, transform = check_fit_inputs(rgb, depth, camera, neighbors, variant, config,
                                                                 gt_depth, transform)
    weight, members = config.blend_weight, blend_members(config)
    config = members[0]
    valid = np.isfinite(depth)
    ring = validation_ring(valid, config.seed) if weight is None else np.zeros_like(valid)
    if weight is None and ((valid & ~ring).sum() < MIN_VALID_PIXELS or ring.sum() < MIN_VALID_PIXELS):
        return fit_once(rgb, depth, camera, neighbors, variant, config, gt_depth=gt_depth, transform=transform,
                        callback=callback, init=init)  # too little to judge by (or to fit without)
    held_out = np.where(ring, np.nan, depth).astype(np.float32) if ring.any() else depth

    def fit_member(k: int) -> DepthResult:  # a warm start fits the first fit's net only
        return fit_once(rgb, held_out, camera, neighbors, variant, members[k], gt_depth=gt_depth,
                        transform=transform, callback=callback, init=init if k == 0 else None)

    fits = run_members(fit_member, 2, parallel_members(config.replace(ensemble=2), variant, depth.shape,
                                                       len(neighbors), callback))
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
    """The two fits ``config.blend_paper`` blends: this config's own fit and the paper recipe's, at the
    same size, budget and seed. ``config.blend_fill`` is left to the caller (it mixes into the blend)."""
    own = config.replace(blend_paper=False)
    return own, own.replace(**get_recipe("paper").overrides)


def fit_with_fill(rgb, depth, camera, neighbors, variant, config, gt_depth, transform, callback, init) -> DepthResult:
    """``config.blend_fill``: the result of ``config`` without it (one fit, a blend or an ensemble) with a
    share of the input's colour-guided fill mixed in (:func:`with_fill`)."""
    config, depth, rgb, neighbors, gt_depth, transform = check_fit_inputs(rgb, depth, camera, neighbors, variant,
                                                                           config, gt_depth, transform)
    def fit(held_out: np.ndarray) -> DepthResult:
        return complete_depth(rgb, held_out, camera, neighbors, variant, config.replace(blend_fill=0.0),
                              gt_depth=gt_depth, transform=transform, callback=callback, init=init)
    return with_fill(fit, depth, rgb, config)


def with_fill(fit, depth: np.ndarray, rgb: np.ndarray, config: FitConfig) -> DepthResult:
    """``fit(depth) -> DepthResult`` with ``config.blend_fill`` f of the colour-guided fill of ``depth`` (H, W)
    metres (NaN holes) mixed in (:func:`mixed_with_fill`). f = None: ``fit`` runs on ``depth`` with
    blobs of its valid pixels held out (:func:`~ddp_lite.method.blend.fill_holdout`), and f is the share
    that best predicts them against a fill of the same held-out input
    (:func:`~ddp_lite.method.blend.best_fill_share`); ``history`` gets ``blend_fill_errors`` (RMSE per
    share, normalised disparity). Too little valid depth to hold any out: the fit alone (f = 0)."""
    share = config.blend_fill
    if share is not None:
        return mixed_with_fill(fit(depth), depth, rgb, share)
    valid = np.isfinite(depth)
    heldout = fill_holdout(valid, config.seed)
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
    transform (:func:`ddp_lite.method.blend.fill_disparity`). ``history`` gets ``blend_fill``."""
    transform = result.transform
    disparity = result.disparity
    if share > 0:  # (share 0 leaves the fit's output as it is, bit for bit)
        disparity = ((1.0 - share) * disparity + share * fill_disparity(depth, rgb, transform)).astype(np.float32)
    return replace(result, disparity=disparity, depth=transform.to_depth(disparity).astype(np.float32),
                   history={**result.history, "blend_fill": share})


def fit_once(rgb, depth, camera, neighbors, variant, config, *, gt_depth=None, transform=None, callback=None,
             init=None, noise=None) -> DepthResult:
    """One fit of :func:`complete_depth` (no ensemble), with an optional fixed network input ``noise``
    (1, C, H, W) (the coarse-to-fine stages pass theirs)."""
    config, depth, rgb, neighbors, gt_depth, transform = check_fit_inputs(
        rgb, depth, camera, neighbors, variant, config, gt_depth, transform)
    H, W = depth.shape
    device = resolve_device(config)
    iterations = config.resolved_iterations(variant)
    spec = get_variant(variant)
    _, w_rgb, w_warp = spec.loss_weights(config.gammas)
    if init is not None and not isinstance(init, DepthResult):
        raise TypeError(f"init must be a DepthResult, got {type(init).__name__}")
    # before any per-fit work: at 12 MP, the SSIM moments alone take seconds (and gigabytes)
    check_memory(config, spec.out_channels, H, W, len(neighbors) if w_warp > 0 else 0, device)
    valid = np.isfinite(depth)
    heldout = (holdout_mask(valid, config.holdout_fraction, config.seed, config.holdout) if config.auto_stop
               else np.zeros_like(valid))
    if (valid & ~heldout).sum() < MIN_VALID_PIXELS:
        heldout = np.zeros_like(valid)
    disparity_in = transform.to_disparity(depth)  # (H, W), NaN in the holes
    target = to_tensor(np.nan_to_num(disparity_in, nan=0.0), device)  # (1, 1, H, W)
    rgb_t = to_tensor(rgb, device) if rgb is not None and w_rgb + w_warp > 0 else None  # (1, 3, H, W)
    nbrs = [(to_tensor(img, device), cam) for img, cam in neighbors] if w_warp > 0 else []
    paper_loss = PaperLoss(spec, config, transform, target, to_tensor(valid & ~heldout, device).bool(), rgb_t,
                           camera, nbrs, device)
    # the unconstrained pixels: holes, and the held-out pixels, which must behave like holes
    hole_terms = HoleTerms(config, ~(valid & ~heldout), rgb_t, rgb, device, disparity_in)

    def loss_fn(output):  # (1, 1 or 4, H, W): Z_out, then I_out
        disparity = output[:, :1]  # one view for every term: the gradients add up in the same order
        total, terms = paper_loss(disparity, output[:, 1:4] if spec.uses_rgb else None)
        return hole_terms.add(disparity, total, terms), terms

    heldout_error = loop.heldout_error_fn(target, heldout, device) if heldout.any() else None
    evaluate = loop.hole_errors_fn(gt_depth, valid, transform, device) if gt_depth is not None else None

    user_callback = None
    if callback is not None:
        def user_callback(iteration, output):
            disparity = output[0, 0].cpu().numpy()
            callback(iteration, {"disparity": disparity, "depth": transform.to_depth(disparity),
                                 "rgb": output[0, 1:4].permute(1, 2, 0).cpu().numpy() if output.shape[1] >= 4 else None})

    # the view's colours as input channels, for the variants that see them (rgb_t is None otherwise)
    image = None
    if config.image_input > 0 and rgb_t is not None:
        image = image_channels(rgb_t, config.image_input, config.image_blur)  # (1, 3, H, W)
    if config.fill_input > 0:  # from the fitted pixels only: the held-out ones stay unseen
        fill = fill_channel(transform.to_disparity(np.where(valid & ~heldout, depth, np.nan)),
                            rgb if spec.uses_rgb else None, config.fill_input)
        fill = to_tensor(fill, device)  # (1, 1, H, W)
        image = fill if image is None else torch.cat([image, fill], dim=1)
    net, noise = loop.build(config, spec.out_channels, H, W, device, init.state if init is not None else None,
                            noise, image)
    start = time.perf_counter()
    output, history, ran, best = loop.run(net, noise, loss_fn, config, iterations, heldout_error, evaluate,
                                          user_callback, description=f"DDP {variant}")
    state = {name: value.detach().cpu().clone() for name, value in net.state_dict().items()}
    seconds = time.perf_counter() - start
    disparity = output[0, 0].cpu().numpy().astype(np.float32)
    out_rgb = output[0, 1:4].permute(1, 2, 0).cpu().numpy().astype(np.float32) if output.shape[1] >= 4 else None
    check_finite_output("disparity", disparity)
    check_finite_output("rgb", out_rgb)
    return DepthResult(depth=transform.to_depth(disparity).astype(np.float32), disparity=disparity, rgb=out_rgb,
                       history=history, transform=transform, iterations=ran, best_iteration=best, seconds=seconds,
                       state=state)
