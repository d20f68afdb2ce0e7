"""Deep Depth Prior: fill the holes of one depth map by fitting a net from fixed noise (paper Sec. 3).

One fit, on inputs checked once (:func:`~ddp_lite.method.input_checks.check_fit_inputs`, and the run's own
arguments, :func:`check_run`): :func:`run_fit` builds the paper's loss
(:mod:`ddp_lite.method.paper.total_loss`) with, when the config asks for them, the kit's hole terms
(:mod:`ddp_lite.method.kit.hole_terms`) and warp term (:mod:`ddp_lite.method.kit.warp_terms`) as its
arguments, joins the kit's net inputs (:mod:`ddp_lite.method.kit.net_inputs`), and hands it to the
loop (:func:`ddp_lite.method.loop.run`). :func:`fit_once` is the two steps in one call. It returns a
:class:`~ddp_lite.method.result.DepthResult`. The entry point,
:func:`~ddp_lite.method.complete.complete_depth`, calls this module, never the reverse, and combines its fits
(an ensemble, the blend with the paper recipe's fit, a share of a classical fill) with
:mod:`ddp_lite.method.kit.combine`.
"""
from __future__ import annotations

import time
import warnings

import numpy as np

from . import loop
from ..core.checks import MIN_VALID_PIXELS, check_callback, check_finite_output
from ..core.progress import FitBar
from .config import FitConfig
from .input_checks import FitInputs, check_fit_inputs
from .kit.hole_terms import HoleTerms
from .kit.net_inputs import net_extras, start_at
from .kit.warp_terms import kit_warp_arguments
from .paper.total_loss import PaperLoss
from .result import DepthResult
from .runtime.device import resolve_device
from .runtime.memory import check_memory
from .misplaced_arguments import names_misplaced_arguments
from .runtime.options import RunOptions, run_options
from .runtime.tensors import to_tensor
from .stopping import held_out_error_fn, held_out_mask

__all__ = ["check_run", "run_fit", "fit_once", "hole_errors_fn"]


def check_run(options, callback=None, init=None) -> RunOptions:
    """A run's own arguments, checked before any work: ``options`` (None → ``RunOptions()``), the ``callback``
    its ``callback_every`` calls, and ``init``, None or a :class:`DepthResult` to warm-start from."""
    options = run_options(options)
    check_callback(callback, options.callback_every)
    if callback is None and options.callback_every:
        from .inert_settings import InertSettingWarning
        warnings.warn(f"options.callback_every={options.callback_every} acts on nothing: no callback is given to call",
                      InertSettingWarning, stacklevel=3)
    if init is not None and not isinstance(init, DepthResult):
        raise TypeError(f"init must be a DepthResult, got {type(init).__name__}")
    return options


@names_misplaced_arguments
def fit_once(rgb, depth, camera, neighbors, variant, config, *, options=None, gt_depth=None, transform=None,
             callback=None, init=None, noise=None) -> DepthResult:
    """One fit (no ensemble, blend or fill): :func:`check_run` and
    :func:`~ddp_lite.method.input_checks.check_fit_inputs`, then :func:`run_fit`."""
    options = check_run(options, callback, init)
    config = FitConfig.for_profile(variant=variant) if config is None else config
    inputs, config = check_fit_inputs(rgb, depth, camera, neighbors, variant, config, gt_depth, transform)
    return run_fit(inputs, config, options, callback=callback, init=init, noise=noise)


def run_fit(inputs: FitInputs, config: FitConfig, options: RunOptions, *, callback=None,
            init: DepthResult | None = None, noise=None) -> DepthResult:
    """One fit of checked ``inputs`` with ``config`` (its ``ensemble``, ``blend_*`` are the combiner's, not
    read here), run as ``options`` say (device, memory limit, progress bar, callback rate), warm-started
    from ``init``'s weights, from the fixed network input ``noise`` (1, C, H, W) when given (the
    coarse-to-fine stages pass theirs)."""
    rgb, depth, camera, neighbors = inputs.rgb, inputs.depth, inputs.camera, inputs.neighbors
    spec, gt_depth, transform, variant = inputs.spec, inputs.gt_depth, inputs.transform, inputs.spec.name
    H, W = depth.shape
    device = resolve_device(options)
    iterations = config.resolved_iterations(spec)
    _, w_rgb, w_warp = spec.loss_weights(config.paper.gammas)
    # before any per-fit work: at 12 MP, the SSIM moments alone take seconds (and gigabytes)
    check_memory(config, options, spec.out_channels, H, W, len(neighbors) if w_warp > 0 else 0, device)
    valid = np.isfinite(depth)
    stopping = config.stopping
    held_out = (held_out_mask(valid, stopping.held_out_fraction, config.paper.seed, stopping.held_out_shape)
                if stopping.auto_stop else np.zeros_like(valid))
    if (valid & ~held_out).sum() < MIN_VALID_PIXELS:
        held_out = np.zeros_like(valid)
    fitted = valid & ~held_out  # the pixels L_disp sees
    disparity_in = transform.to_disparity(depth)  # (H, W), NaN in the holes
    target = to_tensor(np.nan_to_num(disparity_in, nan=0.0), device)  # (1, 1, H, W)
    rgb_t = to_tensor(rgb, device) if rgb is not None and w_rgb + w_warp > 0 else None  # (1, 3, H, W)
    nbrs = [(to_tensor(img, device), cam) for img, cam in neighbors] if w_warp > 0 else []
    fit_mask = to_tensor(fitted, device).bool()
    # the paper's loss, with the kit's warp term, occlusion tests and hole terms (each None or off unless asked
    # for) as its arguments; the hole terms act on the unconstrained pixels: holes, and the held-out pixels
    paper_loss = PaperLoss(spec, config.paper, transform, target, fit_mask, rgb_t, camera, nbrs, device,
                           **kit_warp_arguments(config.warp, config.paper.lambda_w, transform, fit_mask, rgb_t, camera,
                                                nbrs, device),
                           extra_terms=[HoleTerms(config.holes, ~fitted, rgb_t, rgb, device, disparity_in)])

    def loss_fn(output):  # (1, 1 or 4, H, W): Z_out, then I_out
        disparity = output[:, :1]  # one view for every term: the gradients add up in the same order
        return paper_loss(disparity, output[:, 1:4] if spec.uses_rgb else None)

    held_out_error = held_out_error_fn(target, held_out, device) if held_out.any() else None
    evaluate = hole_errors_fn(gt_depth, valid, transform, device) if gt_depth is not None else None

    user_callback = None
    if callback is not None:
        def user_callback(iteration, output):
            disparity = output[0, 0].cpu().numpy()
            callback(iteration, {"disparity": disparity, "depth": transform.to_depth(disparity),
                                 "rgb": output[0, 1:4].permute(1, 2, 0).cpu().numpy() if output.shape[1] >= 4 else None})

    # the kit's extra input channels (the view's colours for the variants that see them, rgb_t None otherwise;
    # a classical fill of the fitted pixels only: the held-out ones stay unseen) and where the output starts
    extra, start_disparity = net_extras(config.net_inputs, rgb_t, rgb if spec.uses_rgb else None,
                                        np.where(fitted, disparity_in, np.nan), device)
    net, noise = loop.build(config, spec.out_channels, H, W, device, init.state if init is not None else None,
                            noise, extra)
    if start_disparity is not None:
        start_at(net, start_disparity)
    start = time.perf_counter()
    progress = FitBar(iterations, f"DDP {variant}", options.progress)
    output, history, ran, best = loop.run(net, noise, loss_fn, config, iterations, held_out_error, evaluate,
                                          user_callback, progress=progress, options=options)
    state = {name: value.detach().cpu().clone() for name, value in net.state_dict().items()}
    seconds = time.perf_counter() - start
    disparity = output[0, 0].cpu().numpy().astype(np.float32)
    out_rgb = output[0, 1:4].permute(1, 2, 0).cpu().numpy().astype(np.float32) if output.shape[1] >= 4 else None
    check_finite_output("disparity", disparity)
    check_finite_output("rgb", out_rgb)
    return DepthResult(depth=transform.to_depth(disparity).astype(np.float32), disparity=disparity, rgb=out_rgb,
                       history=history, transform=transform, iterations=ran, best_iteration=best, seconds=seconds,
                       state=state)


def hole_errors_fn(gt_depth: np.ndarray, valid: np.ndarray, transform, device):
    """``errors(output)`` → {"hole_rmse": disparity RMSE, "hole_rmse_m": depth RMSE in metres} over the
    holes (``valid`` False) where ``gt_depth`` (H, W) metres is known: tracked, never optimised."""
    holes = ~valid & np.isfinite(gt_depth)
    holes_t = to_tensor(holes, device).bool()
    gt_disp_t = to_tensor(np.nan_to_num(transform.to_disparity(gt_depth), nan=0.0), device)
    gt_m_t = to_tensor(np.nan_to_num(np.clip(gt_depth, transform.d_min, transform.d_max), nan=0.0), device)
    n_holes = max(float(holes.sum()), 1.0)

    def evaluate(output):
        if not holes.any():  # no truth in the holes: no error to report (0.0 would read as a perfect fill)
            return {"hole_rmse": float("nan"), "hole_rmse_m": float("nan")}
        disparity = output[:, :1]
        err_disp = ((disparity - gt_disp_t) ** 2 * holes_t).sum() / n_holes
        err_m = ((transform.to_depth(disparity) - gt_m_t) ** 2 * holes_t).sum() / n_holes
        return {"hole_rmse": float(err_disp.sqrt()), "hole_rmse_m": float(err_m.sqrt())}
    return evaluate
