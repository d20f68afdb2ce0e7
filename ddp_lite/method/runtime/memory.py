"""The memory guard: one fit's peak memory, estimated before the net is built, and the limit it must stay under.

The estimate is calibrated against ru_maxrss of fresh processes (CPU, float32, eager PyTorch;
``benchmarks/calibrate_memory.py``): a fixed part (interpreter + torch), 4 bytes × ``FLOATS_PER_UNIT``
per pixel and per "unit" of net width (Σ_k c_k / 4^k over the scales, + the noise channels), and
``BYTES_PER_PARAMETER`` for weights, gradients, Adam's moments and the kept state. A fit whose estimate
exceeds the limit is refused (:func:`check_memory`) rather than left to swap or be killed; fits side by
side divide the limit between them (:mod:`ddp_lite.method.runtime.side_by_side`).
"""
from __future__ import annotations

import os

import torch

from ..paper.nets import SKIP_CHANNELS, UNET_CHANNELS, build_net, count_parameters

__all__ = ["MEMORY_BASE_GB", "FLOATS_PER_UNIT", "BYTES_PER_PARAMETER", "FLOATS_PER_NEIGHBOR_PIXEL",
           "DEFAULT_MEMORY_FRACTION", "estimate_peak_memory_gb", "memory_limit_gb", "check_memory"]

MEMORY_BASE_GB = 0.30  # GiB, as every "GB" here
FLOATS_PER_UNIT = 22.0
BYTES_PER_PARAMETER = 22.0
FLOATS_PER_NEIGHBOR_PIXEL = 150.0  # the warp term per neighbour (grid, samples, SSIM maps); not calibrated
DEFAULT_MEMORY_FRACTION = 0.75


def estimate_peak_memory_gb(config, out_channels: int, height: int, width: int, n_neighbors: int = 0) -> float:
    """An estimate (GB) of the peak memory of one fit of ``config`` (a FitConfig) on a ``height × width``
    image with ``out_channels`` net outputs and ``n_neighbors`` warp partners."""
    paper = config.paper
    channels = paper.channels or (UNET_CHANNELS if paper.net == "unet" else SKIP_CHANNELS)
    levels = len(channels) - 1 if paper.net == "unet" else len(channels)
    factor = 2 ** levels
    pixels = (-(-height // factor) * factor) * (-(-width // factor) * factor)
    first = 0 if paper.net == "unet" else 1  # SkipNet's widest level already runs at half size
    extra = config.net_inputs  # the colour image's 3 channels, the fill's 1
    in_channels = paper.noise_channels + (3 if extra.image_input > 0 else 0) + (1 if extra.fill_input > 0 else 0)
    units = in_channels + sum(c / 4 ** (k + first) for k, c in enumerate(channels))
    with torch.device("meta"):
        parameters = count_parameters(build_net(paper.net, in_channels, out_channels, paper.channels))
    activations = 4.0 * pixels * (FLOATS_PER_UNIT * units + FLOATS_PER_NEIGHBOR_PIXEL * n_neighbors)
    return MEMORY_BASE_GB + (activations + BYTES_PER_PARAMETER * parameters) / 2 ** 30


def memory_limit_gb(options, device: torch.device) -> tuple[float | None, str]:
    """(limit in GB, where it comes from) for a run with these :class:`~ddp_lite.method.runtime.options.RunOptions`
    on ``device``; (None, ...) when the machine's size is unknown."""
    if options.max_memory_gb is not None:
        return float(options.max_memory_gb), "options.max_memory_gb"
    if device.type == "cuda":
        total, what = torch.cuda.get_device_properties(device).total_memory, "GPU memory"
    else:
        try:
            total, what = os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES"), "RAM"
        except (AttributeError, ValueError, OSError):
            return None, "unknown"
    return DEFAULT_MEMORY_FRACTION * total / 2 ** 30, f"{DEFAULT_MEMORY_FRACTION:.0%} of this machine's {what}"


def check_memory(config, options, out_channels: int, height: int, width: int, n_neighbors: int, device) -> None:
    """Refuse, before the net is built, a fit of ``config`` whose estimated peak exceeds the limit of ``options``."""
    limit, source = memory_limit_gb(options, device)
    if limit is None:
        return
    estimate = estimate_peak_memory_gb(config, out_channels, height, width, n_neighbors)
    if estimate > limit:
        raise ValueError(
            f"depth: a {height}×{width} (H×W) fit with this config needs about {estimate:.1f} GB at its peak, more than "
            f"the limit of {limit:.1f} GB ({source}). Downscale the inputs (e.g. cv2.resize, or "
            f"ddp_lite.data.resample.resize_scene for a Scene), use smaller config.channels, or a GPU; or raise the limit with "
            f"options.max_memory_gb (CLI: --max-memory-gb) if you know it fits.")
