"""Deep Image Prior on an image (paper Sec. 3.1; Ulyanov et al. 2018): denoising and inpainting.

The same loop as DDP (:mod:`ddp_lite.method.loop`) with a masked MSE on three colour channels.
"""
from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from . import loop
from ..core.checks import MIN_VALID_PIXELS, check_callback, check_finite_output, check_image
from ..core.progress import FitBar
from .config import FitConfig
from .paper.nets import check_input_size
from .fit_cache import cached
from .runtime.device import resolve_device
from .runtime.memory import check_memory
from .misplaced_arguments import names_misplaced_arguments
from .runtime.options import RunOptions, run_options
from .runtime.tensors import to_tensor
from .stopping import held_out_mask

__all__ = ["ImageResult", "fit_image", "describe_image_fit"]


@dataclass
class ImageResult:
    """What :func:`fit_image` returns: the restored image (H, W, C) and the history."""

    image: np.ndarray
    history: dict
    iterations: int
    best_iteration: int
    seconds: float


def describe_image_fit(config: FitConfig, height: int, width: int) -> str:
    """One line for a notebook's first cell: what :func:`fit_image` runs with ``config`` on an
    ``height``×``width`` image (size, net, iterations, schedule, input). Only what an image fit uses:
    a depth recipe's hole terms and fills do not apply to a photo."""
    paper = config.paper
    extra = paper.noise_channels - 2  # a meshgrid input is (u, v) and then noise channels
    inputs = (("the pixel coordinates" + (f" + {extra} noise channels" if extra > 0 else ""))
              if config.net_inputs.base == "meshgrid" else f"{paper.noise_channels} channels of fixed noise")
    jitter = f", input jitter σ {config.tricks.reg_noise_std:.3g}" if config.tricks.reg_noise_std else ""
    return (f"Deep Image Prior: {height}×{width} (H×W) image, {'UNet' if paper.net == 'unet' else 'SkipNet'} "
            f"{'-'.join(map(str, paper.channels))}, {config.resolved_iterations('rgbd')} iterations, lr {paper.lr:g}, "
            f"auto-stop {'on' if config.stopping.auto_stop else 'off'}, input: {inputs}{jitter}")


@names_misplaced_arguments
@cached(like="image", types=(ImageResult,))
def fit_image(image, mask=None, config: FitConfig | None = None, clean=None, callback=None, *,
              options: RunOptions | None = None) -> ImageResult:
    """Deep Image Prior on an image: fit ``image`` (H, W, 3) float [0, 1] where ``mask`` (H, W) bool
    is True (default: everywhere) with a masked MSE; ``clean`` (H, W, 3), if given, is tracked as PSNR.
    ``options``: how it runs (:class:`RunOptions`: device, memory limit, progress bar, ``callback``'s rate).

    Denoising: pass the noisy image and no mask. Inpainting: pass the mask of known pixels.
    """
    # an image fit runs the RGBD schedule: the profile's ``iterations`` (the paper's 16000)
    config = FitConfig.for_profile(variant="rgbd") if config is None else config
    config.validate()
    image = check_image(image, "image")
    H, W, _ = image.shape
    check_input_size(config.paper.net, config.paper.channels, H, W, "image")
    options = run_options(options)
    check_callback(callback, options.callback_every)
    mask = np.ones((H, W), bool) if mask is None else np.asarray(mask)
    if mask.shape != (H, W) or mask.dtype != bool:
        raise ValueError(f"mask must be bool (H, W) = {(H, W)}, got {mask.dtype} {mask.shape}")
    if mask.sum() < MIN_VALID_PIXELS:
        raise ValueError(f"mask has {int(mask.sum())} known pixels; need at least {MIN_VALID_PIXELS}")
    clean = check_image(clean, "clean", (H, W)) if clean is not None else None
    device = resolve_device(options)
    stopping = config.stopping
    held_out = (held_out_mask(mask, stopping.held_out_fraction, config.paper.seed) if stopping.auto_stop
                else np.zeros_like(mask))
    target = to_tensor(image, device)
    fit_mask = to_tensor(mask & ~held_out, device)
    held_out_t = to_tensor(held_out, device)
    n_fit = float(fit_mask.sum()) * 3

    def loss_fn(output):
        mse = (((output - target) ** 2) * fit_mask).sum() / n_fit
        return mse, {"mse": mse}

    held_out_error = None
    if held_out.any():
        def held_out_error(output):
            return float((((output - target) ** 2) * held_out_t).sum() / (float(held_out.sum()) * 3))

    evaluate = None
    if clean is not None:
        clean_t = to_tensor(clean, device)

        def evaluate(output):
            mse = float(((output.clamp(0, 1) - clean_t) ** 2).mean())
            return {"psnr": 10.0 * np.log10(1.0 / max(mse, 1e-12))}

    user_callback = None
    if callback is not None:
        def user_callback(iteration, output):
            callback(iteration, output[0].permute(1, 2, 0).cpu().numpy())

    check_memory(config, options, 3, H, W, 0, device)
    net, noise = loop.build(config, 3, H, W, device)
    start = time.perf_counter()
    iterations = config.resolved_iterations("rgbd")
    output, history, ran, best = loop.run(net, noise, loss_fn, config, iterations, held_out_error, evaluate,
                                          user_callback, progress=FitBar(iterations, "DIP", options.progress),
                                          options=options)
    restored = output[0].permute(1, 2, 0).cpu().numpy().astype(np.float32)
    check_finite_output("image", restored)
    return ImageResult(image=restored, history=history,
                       iterations=ran, best_iteration=best, seconds=time.perf_counter() - start)
