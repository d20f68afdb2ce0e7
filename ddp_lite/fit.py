"""Deep Depth Prior: fill the holes of one depth map by fitting a net from fixed noise (paper Sec. 3).

:func:`complete_depth` runs one of the three variants (:mod:`ddp_lite.variants`): ``"d"``
(disparity only), ``"rgbd"`` (disparity + colour) and ``"rgbd+warp"`` (plus photo-consistency with
calibrated neighbours). The variants are the same loop (:mod:`ddp_lite.loop`, which also holds the
held-out auto-stop) with different loss weights.

The fit's pieces live beside this module and stay importable from here: :class:`FitConfig`
(:mod:`ddp_lite.config`), :func:`fit_image` (Deep Image Prior on images, :mod:`ddp_lite.dip`),
:func:`complete_depth_coarse_to_fine` (:mod:`ddp_lite.coarse_to_fine`).
"""
from __future__ import annotations

import time
import warnings
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field

import numpy as np
import torch

from . import loop
from .cache import cached
from .camera import Camera, view_overlap, view_parallax
from .checks import MIN_VALID_PIXELS, _unmask, check_callback, check_depth, check_image
from .config import FitConfig, resolve_device, use_bf16
from .dip import ImageResult, fit_image
from .disparity import DisparityTransform
from .loop import (PlateauStopper, check_finite_output, check_memory, estimate_peak_memory_gb, holdout_mask,
                   to_tensor)
from .baselines import NEIGHBOUR_OFFSETS, colorization_affinities
from .losses import (ConstantTarget, affinity_loss, disparity_loss, flatness_loss, flatness_region, rgb_loss, smoothness_loss,
                     smoothness_weights, warp_loss)
from .nets import check_input_size, fill_channel, image_channels
from .variants import VARIANTS, get_variant
from .views import image_and_camera
from .warp import Warper

__all__ = ["FitConfig", "DepthResult", "ImageResult", "complete_depth", "complete_depth_coarse_to_fine", "fit_image",
           "merge", "PlateauStopper", "VARIANTS", "estimate_peak_memory_gb", "use_bf16"]


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
    ddp_depth = np.asarray(_unmask(ddp_depth, "ddp_depth", holes=True))
    if not (np.issubdtype(ddp_depth.dtype, np.floating) or np.issubdtype(ddp_depth.dtype, np.integer)):
        raise TypeError(f"ddp_depth must be an (H, W) array of metres, got dtype {ddp_depth.dtype}")
    ddp_depth = ddp_depth.astype(np.float32)
    if input_depth.shape != ddp_depth.shape:
        raise ValueError(f"input_depth {input_depth.shape} and ddp_depth {ddp_depth.shape} must have the same shape")
    return np.where(np.isfinite(input_depth), input_depth, ddp_depth).astype(np.float32)


# --------------------------------------------------------------------------- input checks

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


def _check_principal_point(camera: Camera, name: str) -> None:
    """Refuse intrinsics that belong to another image size: a principal point more than an image width
    (height) outside the image (640×480's (319.5, 239.5) on a 48×32 image). A crop may move it outside
    the image, but not that far; ``Camera.resized`` scales K with the image."""
    cx, cy = float(camera.K[0, 2]), float(camera.K[1, 2])
    W, H = camera.width, camera.height
    if not (-W <= cx <= 2 * W and -H <= cy <= 2 * H):
        raise ValueError(f"{name}: the principal point ({cx:.6g}, {cy:.6g}) px lies far outside its {W}×{H} (W×H) "
                         f"image; are the intrinsics for another image size? (Camera.resized scales them)")


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


# --------------------------------------------------------------------------- the fit

@cached
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
    if not isinstance(config, FitConfig) or config.ensemble == 1:
        return _fit_one(rgb, depth, camera, neighbors, variant, config, gt_depth=gt_depth, transform=transform,
                        callback=callback, init=init)
    # An ensemble: independent fits from other seeds (other weights, noise and held-out pixels),
    # averaged in disparity. One fit's hole error moves ±10 % and more with the seed; the average
    # keeps what the fits agree on. The inputs are checked once, before the first fit.
    # one transform for every member (the checks derive it from the input depth when None)
    config, _, _, neighbors, _, transform = _check_fit_inputs(rgb, depth, camera, neighbors, variant, config,
                                                              gt_depth, transform)
    def fit_member(k: int) -> DepthResult:
        return _fit_one(rgb, depth, camera, neighbors, variant, config.replace(seed=config.seed + k, ensemble=1),
                        gt_depth=gt_depth, transform=transform, callback=callback, init=init)

    workers = _parallel_members(config, variant, depth.shape, len(neighbors), callback)
    members = _run_members(fit_member, int(config.ensemble), workers)
    disparity = np.mean([m.disparity for m in members], axis=0).astype(np.float32)  # (H, W)
    rgbs = [m.rgb for m in members if m.rgb is not None]
    return DepthResult(depth=transform.to_depth(disparity).astype(np.float32), disparity=disparity,
                       rgb=np.mean(rgbs, axis=0).astype(np.float32) if rgbs else None, history=members[0].history,
                       transform=transform, iterations=sum(m.iterations for m in members),
                       best_iteration=members[0].best_iteration, seconds=sum(m.seconds for m in members),
                       state=members[0].state, fits=len(members))


def _parallel_members(config: FitConfig, variant: str, shape, n_neighbors: int, callback) -> int:
    """How many ensemble members run at once: on a CPU, one per torch thread (each member then
    computes on one thread), as many as fit in memory side by side; 1 with a callback (it may
    draw figures, which wants the main thread) or on a GPU."""
    device = resolve_device(config)
    if device.type != "cpu" or callback is not None:
        return 1
    workers = min(int(config.ensemble), torch.get_num_threads())
    limit, _ = loop.memory_limit_gb(config, device)
    if limit is not None and workers > 1:
        one = estimate_peak_memory_gb(config, get_variant(variant).out_channels, *shape, n_neighbors)
        workers = min(workers, max(1, int(limit // one)))
    return workers


def _run_members(fit_member, members: int, workers: int) -> list:
    """``[fit_member(k) for k in range(members)]``: in rounds of ``workers`` side by side in threads,
    each on one torch thread; what is left over (fewer than ``workers``) in turn on all threads.

    A small net does not keep two cores busy: two one-thread fits side by side do ~1.3× the work
    of one two-thread fit (``benchmarks/bench_ensemble.py --fits``), but one one-thread fit alone
    leaves a core idle, hence whole rounds only. A member run side by side gives the numbers it
    gives with ``torch.set_num_threads(1)``.
    """
    side_by_side = members - members % workers if workers > 1 else 0
    results = []
    if side_by_side:
        threads = torch.get_num_threads()
        torch.set_num_threads(1)
        try:
            with ThreadPoolExecutor(max_workers=workers) as pool:
                results = list(pool.map(fit_member, range(side_by_side)))
        finally:
            torch.set_num_threads(threads)
    return results + [fit_member(k) for k in range(side_by_side, members)]


def _check_fit_inputs(rgb, depth, camera, neighbors, variant, config, gt_depth, transform):
    """Validate a depth fit's inputs before any work: (config, depth, rgb, neighbors, gt_depth, transform)."""
    spec = get_variant(variant)
    config = FitConfig.for_profile(variant=variant) if config is None else config
    if not isinstance(config, FitConfig):
        raise TypeError(f"config must be a FitConfig, got {type(config).__name__}")
    config.validate()
    depth = check_depth(depth)
    H, W = depth.shape
    check_input_size(config.net, config.channels, H, W)
    rgb = check_image(rgb, "rgb", (H, W)) if spec.uses_rgb or rgb is not None else None
    neighbors = _check_neighbors(neighbors)
    if camera is not None and not isinstance(camera, Camera):
        raise TypeError(f"camera must be a ddp_lite.Camera, got {type(camera).__name__}")
    if camera is not None and (camera.height, camera.width) != (H, W):
        raise ValueError(f"camera is {camera.width}×{camera.height} but depth is {W}×{H}")
    for name, cam in ([("camera", camera)] if camera is not None else []) + [
            (f"neighbors[{i}] camera", cam) for i, (_, cam) in enumerate(neighbors)]:
        _check_principal_point(cam, name)
    if spec.needs_neighbors and (camera is None or not neighbors):
        raise ValueError(f"variant {spec.name!r} needs camera and at least one neighbor; use 'rgbd' without them")
    if spec.needs_neighbors:
        _check_overlap(camera, depth, neighbors)
        _check_useful_neighbors(camera, depth, neighbors)
    if gt_depth is not None:  # the kit's convention: NaN = unknown (a 0 would be scored as truth)
        gt_depth = check_depth(gt_depth, "gt_depth", min_valid=0, shape=(H, W))
    transform = DisparityTransform.from_depth(depth, margin=config.disparity_margin) if transform is None else transform
    if not isinstance(transform, DisparityTransform):
        raise TypeError(f"transform must be a DisparityTransform, got {type(transform).__name__}")
    _check_transform(transform, depth)
    return config, depth, rgb, neighbors, gt_depth, transform


def _fit_one(rgb, depth, camera, neighbors, variant, config, *, gt_depth=None, transform=None, callback=None,
             init=None, noise=None) -> DepthResult:
    """One fit of :func:`complete_depth` (no ensemble), with an optional fixed network input ``noise``
    (1, C, H, W) (the coarse-to-fine stages pass theirs)."""
    config, depth, rgb, neighbors, gt_depth, transform = _check_fit_inputs(
        rgb, depth, camera, neighbors, variant, config, gt_depth, transform)
    H, W = depth.shape

    device = resolve_device(config)
    iterations = config.resolved_iterations(variant)
    spec = get_variant(variant)
    w_disp, w_rgb, w_warp = spec.loss_weights(config.gammas)
    if init is not None and not isinstance(init, DepthResult):
        raise TypeError(f"init must be a DepthResult, got {type(init).__name__}")
    # before any per-fit work: at 12 MP, the SSIM moments alone take seconds (and gigabytes)
    check_memory(config, spec.out_channels, H, W, len(neighbors) if w_warp > 0 else 0, device)
    valid = np.isfinite(depth)
    heldout = (holdout_mask(valid, config.holdout_fraction, config.seed, config.holdout) if config.auto_stop
               else np.zeros_like(valid))
    if (valid & ~heldout).sum() < MIN_VALID_PIXELS:
        heldout = np.zeros_like(valid)
    target = to_tensor(np.nan_to_num(transform.to_disparity(depth), nan=0.0), device)  # (1, 1, H, W)
    fit_mask = to_tensor(valid & ~heldout, device).bool()  # (1, 1, H, W)
    heldout_t = to_tensor(heldout, device).bool()
    rgb_t = to_tensor(rgb, device) if rgb is not None and w_rgb + w_warp > 0 else None  # (1, 3, H, W)
    warpers = [Warper(camera, cam, device=device) for _, cam in neighbors] if w_warp > 0 else []
    nbr_images = [to_tensor(img, device) for img, _ in neighbors] if w_warp > 0 else []
    # the targets' share of the loss work, once per fit: holes → 0, mask weights, SSIM moments
    disp_target = ConstantTarget(target, fit_mask)
    rgb_target = ConstantTarget(rgb_t) if rgb_t is not None else None

    smooth_weights = flat_weights = weight_total = None
    if config.smoothness > 0 or config.flatness > 0:
        guide = rgb_t if rgb_t is not None else torch.zeros(1, 3, H, W, device=device)
        # the unconstrained pixels: holes, and the held-out pixels, which must behave like holes
        free = ~(valid & ~heldout)  # (H, W)
        smooth_weights = smoothness_weights(guide, to_tensor(free, device).bool(), config.smoothness_edge,
                                            config.edge_guide)  # (1, 2, H, W)
        # both terms divide by the full weights' sum, also where flatness acts on part of the holes
        weight_total = smooth_weights.sum()
        flat_weights = smooth_weights
        if config.flatness > 0 and config.flatness_reach is not None:
            flat_weights = smooth_weights * to_tensor(flatness_region(free, config.flatness_reach), device)

    affinities = affinity_region = affinity_total = None
    if config.affinity > 0 and rgb is not None:
        affinities = torch.from_numpy(colorization_affinities(rgb))[None].to(device)  # (1, 8, H, W)
        affinity_region = to_tensor(~(valid & ~heldout), device)  # (1, 1, H, W): holes and held-out pixels
        affinity_total = affinity_region.sum()

    def loss_fn(output):
        disparity = output[:, :1]  # (1, 1, H, W)
        terms = {"disp": disparity_loss(disparity, disp_target, lambda_z=config.lambda_z)}
        total = w_disp * terms["disp"]
        if w_rgb > 0:
            terms["rgb"] = rgb_loss(output[:, 1:4], rgb_target, lambda_i=config.lambda_i)
            total = total + w_rgb * terms["rgb"]
        if w_warp > 0:
            ref_depth = transform.to_depth(disparity)  # differentiable: a tensor in, a tensor out
            pairs = [warper(image, ref_depth) for warper, image in zip(warpers, nbr_images)]
            terms["warp"] = warp_loss(rgb_target, [p[0] for p in pairs], [p[1] for p in pairs], config.lambda_w)
            total = total + w_warp * terms["warp"]
        if config.smoothness > 0:
            terms["smooth"] = smoothness_loss(disparity, smooth_weights, weight_total)
            total = total + config.smoothness * terms["smooth"]
        if config.flatness > 0:
            terms["flat"] = flatness_loss(disparity, flat_weights, weight_total)
            total = total + config.flatness * terms["flat"]
        if affinities is not None:
            terms["affinity"] = affinity_loss(disparity, affinities, NEIGHBOUR_OFFSETS, affinity_region, affinity_total)
            total = total + config.affinity * terms["affinity"]
        return total, terms

    heldout_error = None
    if heldout.any():
        n_heldout = float(heldout.sum())

        def heldout_error(output):
            return float(((output[:, :1] - target).abs() * heldout_t).sum() / n_heldout)

    evaluate = None
    if gt_depth is not None:
        holes = ~valid & np.isfinite(gt_depth)
        holes_t = to_tensor(holes, device).bool()
        gt_disp_t = to_tensor(np.nan_to_num(transform.to_disparity(gt_depth), nan=0.0), device)
        gt_m_t = to_tensor(np.nan_to_num(np.clip(gt_depth, transform.d_min, transform.d_max), nan=0.0), device)
        n_holes = max(float(holes.sum()), 1.0)

        def evaluate(output):
            disparity = output[:, :1]
            err_disp = ((disparity - gt_disp_t) ** 2 * holes_t).sum() / n_holes
            err_m = ((transform.to_depth(disparity) - gt_m_t) ** 2 * holes_t).sum() / n_holes
            return {"hole_rmse": float(err_disp.sqrt()), "hole_rmse_m": float(err_m.sqrt())}

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


# built on complete_depth's pieces above, so imported last; importable from here as before
from .coarse_to_fine import complete_depth_coarse_to_fine  # noqa: E402
