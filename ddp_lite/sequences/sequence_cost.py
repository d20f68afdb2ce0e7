"""Paper scale on paper: what completing a whole sequence would cost (``ddp-lite sequence --dry-run``).

``measure_fit_cost`` times one rgbd+warp iteration of a profile's net on this machine and counts
its convolution FLOPs (``torch.utils.flop_counter``), both per pixel; ``estimate_sequence`` scales
them to n views of (H, W): GPU-hours at an *assumed* sustained TFLOP/s, one-thread CPU-hours, and
peak memory per job (``ddp_lite.method.runtime.memory.estimate_peak_memory_gb``); ``format_estimate`` prints that.
"""
from __future__ import annotations

import time

import torch
from torch.utils.flop_counter import FlopCounterMode

from ..method.config import FitConfig
from ..method.complete import complete_depth
from ..method.runtime.memory import estimate_peak_memory_gb
from ..method.runtime.options import RunOptions
from ..world.scenes import make_scene
from .sequence_jobs import N_NEIGHBORS, VARIANT


def measure_fit_cost(profile="paper", size=(96, 128), iterations=(2, 8), threads: int = 1) -> dict:
    """Measure one rgbd+warp iteration of ``profile``'s net on this machine, per pixel.

    A 3-view synthetic scene at ``size`` is fitted once (warm-up), then for ``iterations[0]`` and
    ``iterations[1]`` iterations; the difference of the two times divided by the extra iterations and the pixels is
    the CPU cost of a pixel-iteration (start-up excluded). The convolution FLOPs of one iteration, the warm-up's
    (forward + backward, counted by ``torch.utils.flop_counter``: the net's, and SSIM's Gaussian blurs, 0.2 % of
    the total at the paper's net and 96×128; element-wise work and the warp's sampling are not counted) per pixel
    give a hardware-free cost; the counter imports torch's compiler (``torch._dynamo``, ≈2 s) on its first use.
    The UNet is fully convolutional, so both scale with the pixel count (the CPU cost per pixel still falls a
    little with size, as per-iteration overheads spread: 96×128 is a conservative base). Returns
    {"cpu_seconds_per_pixel_iteration", "flops_per_pixel_iteration", "size", "threads"}: measured once per
    process for each config, size, iterations and threads (the machine is the same at the next dry run), a copy
    each time.
    """
    base = FitConfig.for_profile(profile, variant=VARIANT, auto_stop=False, bf16=False)
    key = (repr(base), tuple(int(n) for n in size), tuple(int(n) for n in iterations), int(threads))
    if key not in _MEASURED:
        _MEASURED[key] = _measure(base, *key[1:])
    return dict(_MEASURED[key])


_MEASURED: dict[tuple, dict] = {}


def _measure(base: FitConfig, size: tuple, iterations: tuple, threads: int) -> dict:
    scene = make_scene("desk", size=size, n_views=3, seed=0)
    quiet = RunOptions(progress=False)
    neighbors = [scene[1].as_neighbor(), scene[2].as_neighbor()]
    previous = torch.get_num_threads()
    torch.set_num_threads(threads)
    try:
        # the warm-up takes first-call costs out of the timing; its one iteration's convolutions are counted
        with FlopCounterMode(display=False) as counter:
            complete_depth(scene[0].rgb, scene[0].depth, scene[0].camera, neighbors, VARIANT,
                           base.replace(iterations=1, lr_milestones=()), options=quiet)
        times = []
        for n in iterations:
            start = time.perf_counter()
            complete_depth(scene[0].rgb, scene[0].depth, scene[0].camera, neighbors, VARIANT,
                           base.replace(iterations=n, lr_milestones=()), options=quiet)
            times.append(time.perf_counter() - start)
    finally:
        torch.set_num_threads(previous)
    pixels = size[0] * size[1]
    return {"cpu_seconds_per_pixel_iteration": (times[1] - times[0]) / (iterations[1] - iterations[0]) / pixels,
            "flops_per_pixel_iteration": counter.get_total_flops() / pixels, "size": size, "threads": threads}


def estimate_sequence(n_views: int, size, profile="paper", cost: dict | None = None, gpu_tflops: float = 5.0) -> dict:
    """Jobs, compute and memory of completing ``n_views`` views of ``size`` (H, W) at ``profile``.

    ``cost``: :func:`measure_fit_cost`'s result (measured now if None). GPU-hours = total convolution
    FLOPs / ``gpu_tflops`` (an *assumed* sustained rate, not a measurement: ~5 TFLOP/s is a third of
    a V100's fp32 peak; replace it with your GPU's by timing one view). CPU-hours use the measured
    single-thread CPU cost. Memory per job: ``ddp_lite.method.runtime.memory.estimate_peak_memory_gb`` (CPU-calibrated)."""
    config = FitConfig.for_profile(profile, variant=VARIANT)
    cost = measure_fit_cost(profile) if cost is None else cost
    H, W = size
    iterations = config.resolved_iterations(VARIANT)
    pixel_iterations = float(n_views) * iterations * H * W
    return {"jobs": int(n_views), "size": (H, W), "iterations": iterations, "profile": getattr(profile, "name", profile),
            "gpu_hours": pixel_iterations * cost["flops_per_pixel_iteration"] / (gpu_tflops * 1e12) / 3600.0,
            "gpu_tflops_assumed": gpu_tflops,
            "cpu_hours_one_thread": pixel_iterations * cost["cpu_seconds_per_pixel_iteration"] / 3600.0,
            "memory_gb_per_job": estimate_peak_memory_gb(config, 4, H, W, N_NEIGHBORS), "cost": cost}


def _round(hours: float) -> str:
    return f"{hours:.2g}" if hours < 10 else f"{hours:.0f}"


def format_estimate(estimate: dict, command: str | None = None) -> str:
    """The dry run's printout of :func:`estimate_sequence`."""
    e, c = estimate, estimate["cost"]
    H, W = e["size"]
    lines = [
        f"{e['jobs']} jobs (one DDP rgbd+warp fit per view), {H}×{W} px (H×W), {e['iterations']} iterations each "
        f"(profile '{e['profile']}')",
        f"  compute: {c['flops_per_pixel_iteration'] / 1e6:.2f} MFLOP per pixel-iteration (convolutions, forward + "
        f"backward, counted at {c['size'][0]}×{c['size'][1]})",
        f"  GPU:     ≈ {_round(e['gpu_hours'])} GPU-hours at an assumed {e['gpu_tflops_assumed']:g} TFLOP/s sustained "
        f"(≈ {60 * e['gpu_hours'] / max(e['jobs'], 1):.1f} min per view)",
        f"  CPU:     ≈ {_round(e['cpu_hours_one_thread'])} CPU-hours on this machine, one thread per fit "
        f"({c['cpu_seconds_per_pixel_iteration'] * 1e6:.2f} µs per pixel-iteration, measured now)",
        f"  memory:  ≈ {e['memory_gb_per_job']:.1f} GB peak per job (runtime.memory.estimate_peak_memory_gb, CPU-calibrated)",
    ]
    if command:
        lines += ["run it on a Dask cluster (one GPU per worker; README 'Your own data' shows dask-jobqueue on Slurm):",
                  f"  {command}"]
    return "\n".join(lines)
