"""The optimisation loop: fit a randomly initialised net, from fixed noise, to one scene.

    θ* = argmin_θ L(f_θ(n)),   output* = f_θ*(n)          (Deep Image Prior, paper Eq. 1)

One loop serves Deep Image Prior on images (:func:`fit_image`) and the three DDP variants
(:func:`complete_depth`): ``"d"`` (disparity only), ``"rgbd"`` (disparity + colour) and
``"rgbd+warp"`` (plus photo-consistency with calibrated neighbours). The variants are the same
code with different loss weights.

Stopping: a run either follows a fixed schedule (the paper's) or stops by itself. For the
latter a small random share of the *valid* pixels is held out of the loss; their error is a
ground-truth-free estimate of how well the net predicts depth it has not seen. The output at
the best held-out error is kept. When it has not improved for ``patience`` iterations (a
plateau) the learning rate is cut by ``lr_gamma``, ``plateau_decays`` times, and the run stops
at the next plateau (:class:`PlateauStopper`). Cutting the rate matters: at a constant rate the
hole error jumps ±10 % between evaluations, and stopping on that noise gave away 13 % on
average against the best a long run reached (``benchmarks/bench_autostop.py``).
"""
from __future__ import annotations

import dataclasses
import functools
import os
import time
import warnings
from dataclasses import dataclass, field

import numpy as np
import torch
from scipy import ndimage
from .progress import progress as tqdm

from .camera import Camera, view_overlap
from .checks import check_bool, check_choice, check_int, check_int_tuple, check_real
from .disparity import DisparityTransform
from .losses import ConstantTarget, disparity_loss, rgb_loss, smoothness_loss, smoothness_weights, warp_loss
from .nets import (DOWNSAMPLINGS, NETS, PADDINGS, SKIP_CHANNELS, UNET_CHANNELS, UPSAMPLINGS, build_net,
                   count_parameters, make_noise)
from .profiles import get_profile
from .variants import VARIANTS, get_variant
from .warp import Warper

__all__ = ["FitConfig", "DepthResult", "ImageResult", "complete_depth", "complete_depth_coarse_to_fine", "fit_image",
           "merge", "PlateauStopper", "VARIANTS"]

HOLDOUTS = ("pixels", "blobs")
MIN_VALID_PIXELS = 16


@dataclass
class FitConfig:
    """Everything a fit needs besides the data. Defaults are the paper's (supplement).

    ``iterations=None`` means 16000 (6000 for depth only); milestones are absolute iterations.
    Use :meth:`for_profile` for the sizes and schedules of ``DDP_PROFILE``.
    """

    net: str = "unet"  # "unet" or "skip"
    channels: tuple | None = None  # encoder widths; None → the paper's
    down: str = "stride"  # UNet down-sampling: "stride" (DIP) or "pool" (Ronneberger)
    up: str = "bilinear"  # UNet up-sampling: "bilinear" or "nearest"
    pad: str = "reflect"  # UNet conv padding: "reflect" (DIP) or "zeros"
    noise_channels: int = 16
    lr: float = 5e-5
    schedule: str = "step"  # "step" (lr × lr_gamma at each milestone) or "cosine" (to 0 at the last iteration)
    iterations: int | None = None
    lr_milestones: tuple = (12000, 15000)
    lr_gamma: float = 0.01
    lambda_z: float = 0.8  # L1 share of L_disp
    lambda_i: float = 0.5  # L1 share of L_rgb
    lambda_w: float = 0.5  # SSIM share of L_warp
    gammas: tuple | None = None  # (γ1, γ2); None → (0.96, 0.02) with warp, (0.98, 0.01) without
    reg_noise_std: float = 0.0  # DIP input jitter: n + σ·N(0, 1) every iteration
    average_outputs: float = 0.0  # DIP output averaging: EMA weight (0.99 in DIP), 0 = off
    ensemble: int = 1  # fits with seeds seed, seed+1, ...; their disparities are averaged
    smoothness: float = 0.0  # weight of an edge-aware second-order smoothness of disparity in the holes (0: the paper)
    smoothness_edge: float = 10.0  # how strongly colour edges relax it: exp(-edge · |∇grey|)
    disparity_margin: float = 1.25  # transform=None: d_min / margin … d_max × margin around the valid depth
    auto_stop: bool = False
    holdout_fraction: float = 0.05  # share of valid pixels held out when auto_stop is on
    holdout: str = "pixels"  # their shape: "pixels" (scattered) or "blobs" (hole-like patches)
    patience: int = 200  # iterations without held-out improvement that make a plateau
    plateau_decays: int = 0  # auto-stop: cut lr by lr_gamma at the first this-many plateaus, stop at the next
    eval_every: int = 10
    seed: int = 0
    device: str | None = None  # None → cuda or mps when available, else cpu
    bf16: bool | None = False  # the network (not the losses) under bfloat16 autocast; None: where the hardware has it
    channels_last: bool = False  # memory format of the network's activations
    progress: bool = True
    callback_every: int = 0
    max_memory_gb: float | None = None  # refuse a fit whose estimated peak exceeds this; None → 75 % of RAM

    @classmethod
    def for_profile(cls, profile=None, variant: str = "rgbd+warp", **overrides) -> "FitConfig":
        """The config of a profile (name, :class:`Profile` or None for ``DDP_PROFILE``)."""
        profile = get_profile(profile)
        iterations = profile.iterations_for(get_variant(variant))
        net = overrides.get("net", "unet")
        values = dict(net=net, channels=profile.channels if net == "unet" else profile.skip_channels,
                      lr=profile.lr, iterations=iterations, lr_milestones=profile.milestones(iterations),
                      lr_gamma=profile.lr_gamma, auto_stop=profile.auto_stop, patience=profile.patience,
                      plateau_decays=profile.plateau_decays, eval_every=profile.eval_every,
                      smoothness=profile.smoothness, smoothness_edge=profile.smoothness_edge, bf16=profile.bf16,
                      ensemble=profile.ensemble)
        values.update(overrides)
        return cls(**values)

    def replace(self, **changes) -> "FitConfig":
        """A copy with some fields changed."""
        return dataclasses.replace(self, **changes)

    def resolved_iterations(self, variant: str) -> int:
        """The iteration count this config runs for ``variant``: ``iterations``, or the paper's."""
        if self.iterations is not None:
            return int(self.iterations)
        return get_variant(variant).paper_iterations

    def validate(self) -> None:
        """Raise ``TypeError``/``ValueError`` naming the first bad field: every number must be finite and
        of its type (no bool for an int, no 2.7 for an iteration count), every choice one of its values."""
        check_choice(self.net, "config.net", NETS)
        if self.channels is not None:
            check_int_tuple(self.channels, "config.channels", minimum=1, min_length=2 if self.net == "unet" else 1)
        for name, choices in (("down", DOWNSAMPLINGS), ("up", UPSAMPLINGS), ("pad", PADDINGS),
                              ("schedule", ("step", "cosine")), ("holdout", HOLDOUTS)):
            check_choice(getattr(self, name), f"config.{name}", choices)
        for name, minimum in (("noise_channels", 1), ("ensemble", 1), ("patience", 1), ("plateau_decays", 0),
                              ("eval_every", 1), ("seed", 0), ("callback_every", 0)):
            check_int(getattr(self, name), f"config.{name}", minimum=minimum)
        if self.iterations is not None:
            check_int(self.iterations, "config.iterations", minimum=1)
        check_int_tuple(self.lr_milestones, "config.lr_milestones", minimum=1)
        for name, low, high, low_open, high_open in (
                ("lr", 0.0, None, True, False), ("lr_gamma", 0.0, None, True, False),
                ("lambda_z", 0.0, 1.0, False, False), ("lambda_i", 0.0, 1.0, False, False),
                ("lambda_w", 0.0, 1.0, False, False), ("reg_noise_std", 0.0, None, False, False),
                ("average_outputs", 0.0, 1.0, False, True), ("smoothness", 0.0, None, False, False),
                ("smoothness_edge", 0.0, None, False, False), ("disparity_margin", 1.0, None, False, False),
                ("holdout_fraction", 0.0, 0.5, True, True)):
            check_real(getattr(self, name), f"config.{name}", low, high, low_open, high_open)
        for name in ("auto_stop", "channels_last", "progress"):
            check_bool(getattr(self, name), f"config.{name}")
        if self.bf16 is not None:  # None: decided by the hardware (use_bf16)
            check_bool(self.bf16, "config.bf16")
        if self.gammas is not None:
            if isinstance(self.gammas, (str, bytes)) or not isinstance(self.gammas, (tuple, list)) or len(self.gammas) != 2:
                raise TypeError(f"config.gammas must be a pair (γ1, γ2), got {self.gammas!r}")
            g1, g2 = (check_real(g, f"config.gammas[{i}]", 0.0, 1.0) for i, g in enumerate(self.gammas))
            if g1 + g2 > 1.0:
                raise ValueError(f"config.gammas must have γ1 + γ2 ≤ 1, got {self.gammas}")
        if self.max_memory_gb is not None:
            check_real(self.max_memory_gb, "config.max_memory_gb", 0.0, None, low_open=True)
        if self.device is not None:
            _device(self)  # a name torch knows and a device this machine has


@dataclass
class DepthResult:
    """What :func:`complete_depth` returns. Arrays are NumPy, (H, W) or (H, W, 3)."""

    depth: np.ndarray  # metres, holes filled
    disparity: np.ndarray  # [0, 1], see ``transform``
    rgb: np.ndarray | None  # the net's colour output (None for depth only)
    history: dict  # per-iteration loss terms; per-evaluation held-out and hole errors; lr_decay_iteration
    transform: DisparityTransform
    iterations: int  # iterations run
    best_iteration: int  # the iteration whose output is returned
    seconds: float
    state: dict | None = field(default=None, repr=False)  # the net's final weights (CPU), for warm starts

    def merged(self, input_depth) -> np.ndarray:
        """"SGM+DDP": the input where it is valid, this result in its holes."""
        return merge(input_depth, self.depth)


@dataclass
class ImageResult:
    """What :func:`fit_image` returns: the restored image (H, W, C) and the history."""

    image: np.ndarray
    history: dict
    iterations: int
    best_iteration: int
    seconds: float


def merge(input_depth, ddp_depth) -> np.ndarray:
    """(H, W) metres: ``input_depth`` where it is finite, ``ddp_depth`` in its holes ("SGM+DDP")."""
    input_depth = np.asarray(input_depth, dtype=np.float32)
    ddp_depth = np.asarray(ddp_depth, dtype=np.float32)
    if input_depth.shape != ddp_depth.shape:
        raise ValueError(f"input_depth {input_depth.shape} and ddp_depth {ddp_depth.shape} must have the same shape")
    return np.where(np.isfinite(input_depth), input_depth, ddp_depth).astype(np.float32)


# --------------------------------------------------------------------------- input checks

def use_bf16(bf16: bool | None, device: torch.device) -> bool:
    """Whether a fit runs its net in bfloat16: ``bf16`` itself, or for ``None`` whether ``device``
    computes bfloat16 natively (a CPU with AVX-512 BF16 or AMX, a CUDA GPU with bf16). Where it
    is emulated it is slower than float32 (0.84× on a CPU without it), where it is native 1.37×
    faster at 96×128 with no worse hole error over 8 seeds (``benchmarks/README.md``)."""
    if bf16 is not None:
        return bool(bf16)
    if device.type == "cuda":
        return torch.cuda.is_bf16_supported()
    return device.type == "cpu" and _cpu_has_native_bf16()


@functools.lru_cache(maxsize=1)
def _cpu_has_native_bf16() -> bool:
    # oneDNN reports bf16 "supported" on any AVX-512 CPU, emulated or not: ask the CPU itself
    try:
        with open("/proc/cpuinfo") as handle:
            flags = next((line.split(":", 1)[1].split() for line in handle if line.startswith("flags")), [])
    except OSError:
        return False
    return "avx512_bf16" in flags or "amx_bf16" in flags


def _device(config: FitConfig) -> torch.device:
    if config.device is not None:
        if not isinstance(config.device, (str, torch.device)):
            raise TypeError(f"config.device must be None or a name like 'cpu', 'cuda', 'cuda:0', 'mps', "
                            f"got {type(config.device).__name__}")
        try:
            device = torch.device(config.device)
        except RuntimeError:
            raise ValueError(f"config.device must be None, 'cpu', 'cuda[:N]' or 'mps', got {config.device!r}") from None
        mps = getattr(torch.backends, "mps", None)
        available = {"cpu": True, "cuda": torch.cuda.is_available(),
                     "mps": mps is not None and mps.is_available()}
        if not available.get(device.type, False):
            raise ValueError(f"config.device={config.device!r}: this machine has no usable {device.type} device; "
                             f"use 'cpu' or None (picks cuda/mps when present)")
        if device.type == "cuda" and device.index is not None and device.index >= torch.cuda.device_count():
            raise ValueError(f"config.device={config.device!r}: only {torch.cuda.device_count()} CUDA device(s)")
        return device
    if torch.cuda.is_available():
        return torch.device("cuda")
    if getattr(torch.backends, "mps", None) is not None and torch.backends.mps.is_available():
        return torch.device("mps")
    return torch.device("cpu")


def _check_image(image, name: str, shape=None) -> np.ndarray:
    if isinstance(image, torch.Tensor):
        raise TypeError(f"{name} must be a NumPy array (H, W, 3), got a torch tensor")
    array = np.asarray(image)
    if array.dtype == np.uint8:
        array = array.astype(np.float32) / 255.0
    if not np.issubdtype(array.dtype, np.floating):
        raise TypeError(f"{name} must be float in [0, 1] (or uint8), got dtype {array.dtype}")
    if array.ndim != 3 or array.shape[2] != 3:
        raise ValueError(f"{name} must have shape (H, W, 3), got {array.shape}")
    if shape is not None and array.shape[:2] != shape:
        raise ValueError(f"{name} must be {shape[0]}×{shape[1]} like depth, got {array.shape[0]}×{array.shape[1]}")
    if not np.all(np.isfinite(array)):
        raise ValueError(f"{name} must contain only finite values")
    if array.min() < -1e-6 or array.max() > 1 + 1e-6:
        raise ValueError(f"{name} must lie in [0, 1], got range [{array.min():.3g}, {array.max():.3g}]")
    return np.clip(array, 0.0, 1.0).astype(np.float32)


def _check_depth(depth, name: str = "depth", allow_holes: bool = True) -> np.ndarray:
    if isinstance(depth, torch.Tensor):
        raise TypeError(f"{name} must be a NumPy array (H, W), got a torch tensor")
    array = np.asarray(depth)
    if not np.issubdtype(array.dtype, np.floating):
        raise TypeError(f"{name} must be float metres with NaN holes, got dtype {array.dtype}")
    if array.ndim != 2:
        raise ValueError(f"{name} must have shape (H, W), got {array.shape}")
    finite = np.isfinite(array)
    if np.any(np.isinf(array)):
        raise ValueError(f"{name} contains inf; mark holes with NaN (loaders convert a dataset's own marker)")
    if np.any(array[finite] <= 0):
        raise ValueError(f"{name} must be positive metres where valid, got minimum {array[finite].min():.3g}")
    if finite.sum() < MIN_VALID_PIXELS:
        raise ValueError(f"{name} has {int(finite.sum())} valid pixels; need at least {MIN_VALID_PIXELS}")
    if not allow_holes and not finite.all():
        raise ValueError(f"{name} must have no holes")
    return array.astype(np.float32)


def _check_neighbors(neighbors) -> list[tuple[np.ndarray, Camera]]:
    if isinstance(neighbors, (np.ndarray, torch.Tensor, str)) or hasattr(neighbors, "camera"):
        raise TypeError(f"neighbors must be a list of (rgb, Camera) pairs or Views, got one "
                        f"{type(neighbors).__name__}; wrap a single view in a list")
    checked = []
    for i, item in enumerate(neighbors):
        if hasattr(item, "camera"):
            rgb, camera = item.rgb, item.camera
        elif isinstance(item, (tuple, list)) and len(item) == 2:
            rgb, camera = item
        else:
            raise TypeError(f"neighbors[{i}] must be an (rgb, Camera) pair or a View, got {type(item).__name__}")
        if not isinstance(camera, Camera):
            raise TypeError(f"neighbors[{i}] must be an (rgb, Camera) pair or a View, got camera {type(camera).__name__}")
        checked.append((_check_image(rgb, f"neighbors[{i}] rgb", (camera.height, camera.width)), camera))
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


def _to_tensor(array: np.ndarray, device) -> torch.Tensor:
    """(H, W) → (1, 1, H, W); (H, W, C) → (1, C, H, W)."""
    tensor = torch.from_numpy(np.ascontiguousarray(array, dtype=np.float32))
    tensor = tensor[None, None] if tensor.ndim == 2 else tensor.permute(2, 0, 1)[None]
    return tensor.contiguous().to(device)


# --------------------------------------------------------------------------- the loop

class PlateauStopper:
    """Ground-truth-free stopping on a held-out error, checked every ``eval_every`` iterations.

    A *plateau* is ``patience`` iterations without a new best held-out error. At each of the
    first ``decays`` plateaus the learning rate is cut (``"decay"``) and the count restarts; at
    the next one the run stops (``"stop"``). With ``decays=0`` this is plain early stopping.
    The caller keeps the output of the best evaluation (``improved``).

    Example:
        >>> stopper = PlateauStopper(patience=20, eval_every=10, decays=1)
        >>> [stopper.update(e) for e in (3.0, 2.0, 2.5, 2.4, 1.0, 1.5, 1.2)]
        ['improved', 'improved', '', 'decay', 'improved', '', 'stop']
    """

    def __init__(self, patience: int, eval_every: int, decays: int = 0):
        self.patience, self.eval_every, self.decays_left = patience, eval_every, decays
        self.best, self.since_best = float("inf"), 0

    def update(self, error: float) -> str:
        """Feed one held-out error; returns ``"improved"``, ``"decay"``, ``"stop"`` or ``""``."""
        if error < self.best:
            self.best, self.since_best = error, 0
            return "improved"
        self.since_best += self.eval_every
        if self.since_best < self.patience:
            return ""
        if self.decays_left > 0:
            self.decays_left -= 1
            self.since_best = 0
            return "decay"
        return "stop"


def _run(net, noise, loss_fn, config: FitConfig, iterations: int, heldout_error=None, evaluate=None,
         callback=None, description: str = "fit"):
    """Adam on ``loss_fn(net(noise))``; returns (kept output, history, iterations run, best iteration)."""
    # the fused kernel updates all parameters in one call: ~10-25 % faster per iteration on CPU
    optimizer = torch.optim.Adam(net.parameters(), lr=config.lr, fused=noise.device.type in ("cpu", "cuda"))
    if config.schedule == "cosine":
        scheduler = torch.optim.lr_scheduler.CosineAnnealingLR(optimizer, T_max=iterations)
    else:
        milestones = [m for m in config.lr_milestones if m < iterations]
        scheduler = torch.optim.lr_scheduler.MultiStepLR(optimizer, milestones, gamma=config.lr_gamma)
    autocast = torch.autocast(noise.device.type, dtype=torch.bfloat16, enabled=use_bf16(config.bf16, noise.device))
    if config.channels_last:
        net, noise = net.to(memory_format=torch.channels_last), noise.contiguous(memory_format=torch.channels_last)
    jitter = torch.Generator(device=noise.device).manual_seed(config.seed + 1) if config.reg_noise_std else None
    terms_log = None  # (iterations, n_terms) kept on the device: no host read per iteration
    lrs = []
    evals = {"eval_iteration": [], "heldout": [], "lr_decay_iteration": []}
    averaged = best_output = None
    best_iteration = 0
    stop_check = config.auto_stop and heldout_error is not None
    stopper = PlateauStopper(config.patience, config.eval_every, config.plateau_decays)
    bar = tqdm(range(iterations), desc=description, disable=not config.progress, leave=False)
    it = -1
    for it in bar:
        net_input = noise
        if jitter is not None:
            net_input = noise + config.reg_noise_std * torch.randn(noise.shape, generator=jitter, device=noise.device)
        with autocast:
            output = net(net_input)
        output = output.float().contiguous()
        total, terms = loss_fn(output)
        optimizer.zero_grad(set_to_none=True)
        total.backward()
        lrs.append(optimizer.param_groups[0]["lr"])  # a Python float: no device sync
        optimizer.step()
        scheduler.step()
        if terms_log is None:
            names = ["loss", *terms]
            terms_log = torch.zeros(iterations, len(names), device=noise.device)
        terms_log[it] = torch.stack([total.detach(), *(t.detach() for t in terms.values())])
        current = output.detach()
        if config.average_outputs:
            averaged = current if averaged is None else config.average_outputs * averaged + (1 - config.average_outputs) * current
            current = averaged
        last = it + 1 == iterations
        if (it + 1) % config.eval_every == 0 or last:
            evals["eval_iteration"].append(it + 1)
            error = float(heldout_error(current)) if heldout_error is not None else float("nan")
            evals["heldout"].append(error)
            for key, value in (evaluate(current) if evaluate is not None else {}).items():
                evals.setdefault(key, []).append(value)
            if stop_check:
                event = stopper.update(error)
                if event == "improved":
                    best_iteration, best_output = it + 1, current.clone()
                elif event == "decay":
                    for group in optimizer.param_groups:
                        group["lr"] *= config.lr_gamma
                    evals["lr_decay_iteration"].append(it + 1)
                elif event == "stop":
                    break
                bar.set_postfix(heldout=f"{error:.4f}", refresh=False)
        if callback is not None and config.callback_every and (it + 1) % config.callback_every == 0:
            callback(it + 1, current)
    bar.close()
    history = {name: column.cpu().numpy()[: it + 1] for name, column in zip(names, terms_log.T)}
    history["lr"] = np.asarray(lrs)
    history.update({key: np.asarray(values) for key, values in evals.items()})
    if best_output is None:
        best_output, best_iteration = current, it + 1
    return best_output, history, it + 1, best_iteration


def _build(config: FitConfig, out_channels: int, height: int, width: int, device, init_state=None, noise=None):
    with torch.random.fork_rng(devices=[]):  # deterministic init without touching the caller's RNG
        torch.manual_seed(config.seed)
        options = dict(down=config.down, up=config.up, pad=config.pad) if config.net == "unet" else {}
        net = build_net(config.net, config.noise_channels, out_channels, config.channels, **options)
    if init_state is not None:
        try:
            net.load_state_dict(init_state)
        except RuntimeError as error:
            raise ValueError(f"init: its weights do not fit this config's network ({error.args[0].splitlines()[0]})")
    if noise is None:
        noise = make_noise(config.noise_channels, height, width, seed=config.seed)
    elif tuple(noise.shape) != (1, config.noise_channels, height, width):
        raise ValueError(f"noise must be (1, {config.noise_channels}, {height}, {width}), got {tuple(noise.shape)}")
    return net.to(device), noise.to(device)


# Peak memory of one fit, calibrated against ru_maxrss of fresh processes (CPU, float32, eager PyTorch;
# benchmarks/calibrate_memory.py): a fixed part (interpreter + torch), 4 bytes × FLOATS_PER_UNIT per
# pixel and per "unit" of net width (Σ_k c_k / 4^k over the scales, + the noise channels), and
# BYTES_PER_PARAMETER for weights, gradients, Adam's moments and the kept state.
MEMORY_BASE_GB = 0.30  # GiB, as every "GB" here
FLOATS_PER_UNIT = 22.0
BYTES_PER_PARAMETER = 22.0
FLOATS_PER_NEIGHBOR_PIXEL = 150.0  # the warp term per neighbour (grid, samples, SSIM maps); not calibrated
DEFAULT_MEMORY_FRACTION = 0.75


def estimate_peak_memory_gb(config: FitConfig, out_channels: int, height: int, width: int,
                            n_neighbors: int = 0) -> float:
    """An estimate (GB) of the peak memory of one fit of ``config`` on a ``height × width`` image."""
    channels = config.channels or (UNET_CHANNELS if config.net == "unet" else SKIP_CHANNELS)
    levels = len(channels) - 1 if config.net == "unet" else len(channels)
    factor = 2 ** levels
    pixels = (-(-height // factor) * factor) * (-(-width // factor) * factor)
    first = 0 if config.net == "unet" else 1  # SkipNet's widest level already runs at half size
    units = config.noise_channels + sum(c / 4 ** (k + first) for k, c in enumerate(channels))
    with torch.device("meta"):
        parameters = count_parameters(build_net(config.net, config.noise_channels, out_channels, config.channels))
    activations = 4.0 * pixels * (FLOATS_PER_UNIT * units + FLOATS_PER_NEIGHBOR_PIXEL * n_neighbors)
    return MEMORY_BASE_GB + (activations + BYTES_PER_PARAMETER * parameters) / 2 ** 30


def _memory_limit_gb(config: FitConfig, device: torch.device) -> tuple[float | None, str]:
    """(limit in GB, where it comes from); (None, ...) when the machine's size is unknown."""
    if config.max_memory_gb is not None:
        return float(config.max_memory_gb), "config.max_memory_gb"
    if device.type == "cuda":
        total, what = torch.cuda.get_device_properties(device).total_memory, "GPU memory"
    else:
        try:
            total, what = os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES"), "RAM"
        except (AttributeError, ValueError, OSError):
            return None, "unknown"
    return DEFAULT_MEMORY_FRACTION * total / 2 ** 30, f"{DEFAULT_MEMORY_FRACTION:.0%} of this machine's {what}"


def _check_memory(config: FitConfig, out_channels: int, height: int, width: int, n_neighbors: int, device) -> None:
    """Refuse, before the net is built, a fit whose estimated peak exceeds the limit."""
    limit, source = _memory_limit_gb(config, device)
    if limit is None:
        return
    estimate = estimate_peak_memory_gb(config, out_channels, height, width, n_neighbors)
    if estimate > limit:
        raise ValueError(
            f"depth: a {width}×{height} fit with this config needs about {estimate:.1f} GB at its peak, more than "
            f"the limit of {limit:.1f} GB ({source}). Downscale the inputs (e.g. cv2.resize, or "
            f"datasets.resize_scene for a Scene), use smaller config.channels, or a GPU; or raise the limit with "
            f"config.max_memory_gb (CLI: --max-memory-gb) if you know it fits.")


def _check_finite_output(name: str, array) -> None:
    """A fit must never return NaN or inf: raise instead (the optimisation diverged)."""
    if array is not None and not np.all(np.isfinite(array)):
        bad = int(np.size(array) - np.isfinite(array).sum())
        raise FloatingPointError(f"the fit's {name} has {bad} non-finite value(s) of {np.size(array)}: the "
                                 f"optimisation diverged. Lower config.lr, or check the inputs and init.")


def _holdout_mask(valid: np.ndarray, fraction: float, seed: int, shape: str = "pixels") -> np.ndarray:
    """A random share ``fraction`` of the valid pixels (H, W) bool, seeded: scattered single pixels, or
    ``"blobs"`` (smooth random blobs, blur scale min(H, W)/24 px, like the holes a fit must fill: a
    single held-out pixel is predicted from its neighbours by any smooth fit, a blob is not)."""
    rng = np.random.default_rng(seed + 12345)
    if shape == "pixels":
        return valid & (rng.random(valid.shape) < fraction)
    H, W = valid.shape
    field = ndimage.gaussian_filter(rng.standard_normal((H, W)), max(1.0, min(H, W) / 24.0), mode="wrap")
    return valid & (field <= np.quantile(field[valid], fraction))


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
    if callback is not None and not callable(callback):
        raise TypeError(f"callback must be a function callback(iteration, outputs), got {type(callback).__name__}")
    if not isinstance(config, FitConfig) or config.ensemble == 1:
        return _complete_depth(rgb, depth, camera, neighbors, variant, config, gt_depth, transform, callback, init)
    # An ensemble: independent fits from other seeds (other weights, noise and held-out pixels),
    # averaged in disparity. One fit's hole error moves ±10 % and more with the seed; the average
    # keeps what the fits agree on. The inputs are checked once, before the first fit.
    # one transform for every member (the checks derive it from the input depth when None)
    config, _, _, neighbors, _, transform = _check_fit_inputs(rgb, depth, camera, neighbors, variant, config,
                                                              gt_depth, transform)
    members = [_complete_depth(rgb, depth, camera, neighbors, variant, config.replace(seed=config.seed + k, ensemble=1),
                               gt_depth, transform, callback, init) for k in range(int(config.ensemble))]
    disparity = np.mean([m.disparity for m in members], axis=0).astype(np.float32)  # (H, W)
    rgbs = [m.rgb for m in members if m.rgb is not None]
    return DepthResult(depth=transform.to_depth(disparity).astype(np.float32), disparity=disparity,
                       rgb=np.mean(rgbs, axis=0).astype(np.float32) if rgbs else None, history=members[0].history,
                       transform=transform, iterations=sum(m.iterations for m in members),
                       best_iteration=members[0].best_iteration, seconds=sum(m.seconds for m in members),
                       state=members[0].state)


def _check_fit_inputs(rgb, depth, camera, neighbors, variant, config, gt_depth, transform):
    """Validate a depth fit's inputs before any work: (config, depth, rgb, neighbors, gt_depth, transform)."""
    spec = get_variant(variant)
    config = FitConfig.for_profile(variant=variant) if config is None else config
    if not isinstance(config, FitConfig):
        raise TypeError(f"config must be a FitConfig, got {type(config).__name__}")
    config.validate()
    depth = _check_depth(depth)
    H, W = depth.shape
    rgb = _check_image(rgb, "rgb", (H, W)) if spec.uses_rgb or rgb is not None else None
    neighbors = _check_neighbors(neighbors)
    if camera is not None and not isinstance(camera, Camera):
        raise TypeError(f"camera must be a ddp_lite.Camera, got {type(camera).__name__}")
    if camera is not None and (camera.height, camera.width) != (H, W):
        raise ValueError(f"camera is {camera.width}×{camera.height} but depth is {W}×{H}")
    if spec.needs_neighbors and (camera is None or not neighbors):
        raise ValueError(f"variant {spec.name!r} needs camera and at least one neighbor; use 'rgbd' without them")
    if spec.needs_neighbors:
        _check_overlap(camera, depth, neighbors)
    if gt_depth is not None:
        gt_depth = np.asarray(gt_depth, dtype=np.float32)
        if gt_depth.shape != (H, W):
            raise ValueError(f"gt_depth must be {(H, W)} like depth, got {gt_depth.shape}")
    transform = DisparityTransform.from_depth(depth, margin=config.disparity_margin) if transform is None else transform
    if not isinstance(transform, DisparityTransform):
        raise TypeError(f"transform must be a DisparityTransform, got {type(transform).__name__}")
    return config, depth, rgb, neighbors, gt_depth, transform


def _complete_depth(rgb, depth, camera, neighbors, variant, config, gt_depth, transform, callback, init,
                    noise=None) -> DepthResult:
    """:func:`complete_depth` with an optional fixed network input ``noise`` (1, C, H, W)."""
    config, depth, rgb, neighbors, gt_depth, transform = _check_fit_inputs(
        rgb, depth, camera, neighbors, variant, config, gt_depth, transform)
    H, W = depth.shape

    device = _device(config)
    iterations = config.resolved_iterations(variant)
    spec = get_variant(variant)
    w_disp, w_rgb, w_warp = spec.loss_weights(config.gammas)
    valid = np.isfinite(depth)
    heldout = (_holdout_mask(valid, config.holdout_fraction, config.seed, config.holdout) if config.auto_stop
               else np.zeros_like(valid))
    if (valid & ~heldout).sum() < MIN_VALID_PIXELS:
        heldout = np.zeros_like(valid)
    target = _to_tensor(np.nan_to_num(transform.to_disparity(depth), nan=0.0), device)  # (1, 1, H, W)
    fit_mask = _to_tensor(valid & ~heldout, device).bool()  # (1, 1, H, W)
    heldout_t = _to_tensor(heldout, device).bool()
    rgb_t = _to_tensor(rgb, device) if rgb is not None and w_rgb + w_warp > 0 else None  # (1, 3, H, W)
    warpers = [Warper(camera, cam, device=device) for _, cam in neighbors] if w_warp > 0 else []
    nbr_images = [_to_tensor(img, device) for img, _ in neighbors] if w_warp > 0 else []
    near, far, constant = transform.near, transform.far, transform.constant
    # the targets' share of the loss work, once per fit: holes → 0, mask weights, SSIM moments
    disp_target = ConstantTarget(target, fit_mask)
    rgb_target = ConstantTarget(rgb_t) if rgb_t is not None else None

    def to_metres(disparity):  # differentiable twin of transform.to_depth
        return 1.0 / (disparity * (near - far) + far) - constant

    smooth_weights = None
    if config.smoothness > 0:
        guide = rgb_t if rgb_t is not None else torch.zeros(1, 3, H, W, device=device)
        # the unconstrained pixels: holes, and the held-out pixels, which must behave like holes
        smooth_weights = smoothness_weights(guide, _to_tensor(~(valid & ~heldout), device).bool(), config.smoothness_edge)

    def loss_fn(output):
        disparity = output[:, :1]  # (1, 1, H, W)
        terms = {"disp": disparity_loss(disparity, disp_target, lambda_z=config.lambda_z)}
        total = w_disp * terms["disp"]
        if w_rgb > 0:
            terms["rgb"] = rgb_loss(output[:, 1:4], rgb_target, config.lambda_i)
            total = total + w_rgb * terms["rgb"]
        if w_warp > 0:
            ref_depth = to_metres(disparity)
            pairs = [warper(image, ref_depth) for warper, image in zip(warpers, nbr_images)]
            terms["warp"] = warp_loss(rgb_target, [p[0] for p in pairs], [p[1] for p in pairs], config.lambda_w)
            total = total + w_warp * terms["warp"]
        if smooth_weights is not None:
            terms["smooth"] = smoothness_loss(disparity, smooth_weights)
            total = total + config.smoothness * terms["smooth"]
        return total, terms

    heldout_error = None
    if heldout.any():
        n_heldout = float(heldout.sum())

        def heldout_error(output):
            return float(((output[:, :1] - target).abs() * heldout_t).sum() / n_heldout)

    evaluate = None
    if gt_depth is not None:
        holes = ~valid & np.isfinite(gt_depth)
        holes_t = _to_tensor(holes, device).bool()
        gt_disp_t = _to_tensor(np.nan_to_num(transform.to_disparity(gt_depth), nan=0.0), device)
        gt_m_t = _to_tensor(np.nan_to_num(np.clip(gt_depth, transform.d_min, transform.d_max), nan=0.0), device)
        n_holes = max(float(holes.sum()), 1.0)

        def evaluate(output):
            disparity = output[:, :1]
            err_disp = ((disparity - gt_disp_t) ** 2 * holes_t).sum() / n_holes
            err_m = ((to_metres(disparity) - gt_m_t) ** 2 * holes_t).sum() / n_holes
            return {"hole_rmse": float(err_disp.sqrt()), "hole_rmse_m": float(err_m.sqrt())}

    user_callback = None
    if callback is not None:
        def user_callback(iteration, output):
            disparity = output[0, 0].cpu().numpy()
            callback(iteration, {"disparity": disparity, "depth": transform.to_depth(disparity),
                                 "rgb": output[0, 1:4].permute(1, 2, 0).cpu().numpy() if output.shape[1] >= 4 else None})

    if init is not None and not isinstance(init, DepthResult):
        raise TypeError(f"init must be a DepthResult, got {type(init).__name__}")
    _check_memory(config, spec.out_channels, H, W, len(warpers), device)
    net, noise = _build(config, spec.out_channels, H, W, device, init.state if init is not None else None,
                        noise)
    start = time.perf_counter()
    output, history, ran, best = _run(net, noise, loss_fn, config, iterations, heldout_error, evaluate,
                                      user_callback, description=f"DDP {variant}")
    state = {name: value.detach().cpu().clone() for name, value in net.state_dict().items()}
    seconds = time.perf_counter() - start
    disparity = output[0, 0].cpu().numpy().astype(np.float32)
    out_rgb = output[0, 1:4].permute(1, 2, 0).cpu().numpy().astype(np.float32) if output.shape[1] >= 4 else None
    _check_finite_output("disparity", disparity)
    _check_finite_output("rgb", out_rgb)
    return DepthResult(depth=transform.to_depth(disparity).astype(np.float32), disparity=disparity, rgb=out_rgb,
                       history=history, transform=transform, iterations=ran, best_iteration=best, seconds=seconds,
                       state=state)


def _pad_to_multiple(array: np.ndarray, scale: int, mode: str) -> np.ndarray:
    """Pad (H, W[, C]) at the bottom and right to multiples of ``scale``: NaN (``"nan"``) or edge copies."""
    pad_h, pad_w = (-array.shape[0]) % scale, (-array.shape[1]) % scale
    if not (pad_h or pad_w):
        return array
    widths = ((0, pad_h), (0, pad_w)) + ((0, 0),) * (array.ndim - 2)
    return np.pad(array, widths, mode="constant", constant_values=np.nan) if mode == "nan" else np.pad(array, widths, mode="edge")


def _downsample_depth(depth: np.ndarray, scale: int) -> np.ndarray:
    """(H, W) metres with NaN holes → (⌈H/scale⌉, ⌈W/scale⌉): each ``scale × scale`` block becomes the
    nearest surface in it (min-pooling, no averaging across depth edges), or a hole (NaN) if any
    of its pixels is one: holes stay holes, and no coarse depth is made of partly unknown blocks."""
    padded = _pad_to_multiple(np.asarray(depth, np.float32), scale, "nan")
    h, w = padded.shape[0] // scale, padded.shape[1] // scale
    blocks = padded.reshape(h, scale, w, scale).transpose(0, 2, 1, 3).reshape(h, w, scale * scale)
    out = np.full((h, w), np.nan, np.float32)
    full = np.isfinite(blocks).all(axis=-1)
    out[full] = blocks[full].min(axis=-1)
    return out


def _downsample_image(image: np.ndarray, scale: int) -> np.ndarray:
    """(H, W, C) → (⌈H/scale⌉, ⌈W/scale⌉, C) by area averaging (edge-padded to a multiple of ``scale``)."""
    padded = _pad_to_multiple(np.asarray(image, np.float32), scale, "edge")
    h, w = padded.shape[0] // scale, padded.shape[1] // scale
    return padded.reshape(h, scale, w, scale, -1).mean(axis=(1, 3)).astype(np.float32)


def _downsample_camera(camera: Camera, scale: int) -> Camera:
    """The camera of an image padded (bottom/right) to multiples of ``scale`` and shrunk by ``scale``."""
    height, width = -(-camera.height // scale) * scale, -(-camera.width // scale) * scale
    return Camera(camera.K, camera.cam_from_world, width, height).resized(width // scale, height // scale)


def complete_depth_coarse_to_fine(rgb, depth, camera: Camera | None = None, neighbors=(), variant: str = "rgbd+warp",
                                  config: FitConfig | None = None, gt_depth=None,
                                  transform: DisparityTransform | None = None, coarse_fraction: float = 0.5,
                                  scale: int = 2) -> DepthResult:
    """:func:`complete_depth` in two stages: first at 1/``scale`` size, then at full size from the coarse weights.

    The coarse stage runs ``round(coarse_fraction · iterations)`` iterations (no auto-stop) on the
    inputs shrunk by ``scale``: images by area averaging, depth (and ``gt_depth``) by min-pooling
    where a block holding any hole stays a hole, cameras via :meth:`Camera.resized` (images are
    padded bottom/right to a multiple of ``scale`` first). The UNet is fully convolutional, so
    its weights carry over; the full-size stage sees the coarse noise upsampled bilinearly, the
    same input at twice the resolution. It runs the remaining iterations with ``config`` as
    given (auto-stop included); the learning-rate schedule continues across the two stages.

    Args:
        rgb: (H, W, 3) float in [0, 1] (may be None for ``variant="d"``).
        depth: (H, W) float metres, NaN = hole.
        camera, neighbors, variant, config, gt_depth, transform: as in :func:`complete_depth`.
        coarse_fraction: share of the iterations spent at the coarse size, in (0, 1).
        scale: integer shrink factor of the coarse stage, ≥ 2.

    Returns:
        :class:`DepthResult` of the full-size stage, ``.depth`` (H, W) metres. ``history`` joins
        both stages (full-size iterations offset by the coarse count; coarse hole errors are on
        the coarse grid) and adds ``eval_scale`` (scale of each evaluation), ``stage_iterations``
        and ``stage_seconds``; ``seconds`` and ``iterations`` are the totals.

    Example:
        >>> depth = np.full((32, 32), 2.0, np.float32); depth[10:20, 10:20] = np.nan
        >>> cfg = FitConfig(channels=(8, 16), lr=1e-2, iterations=6, progress=False)
        >>> complete_depth_coarse_to_fine(None, depth, variant="d", config=cfg).depth.shape
        (32, 32)
    """
    if isinstance(scale, bool) or not isinstance(scale, (int, np.integer)) or scale < 2:
        raise ValueError(f"scale must be an integer ≥ 2, got {scale!r}")
    if not 0.0 < float(coarse_fraction) < 1.0:
        raise ValueError(f"coarse_fraction must lie in (0, 1), got {coarse_fraction!r}")
    config, depth, rgb, neighbors, gt_depth, transform = _check_fit_inputs(
        rgb, depth, camera, neighbors, variant, config, gt_depth, transform)
    scale = int(scale)
    H, W = depth.shape
    iterations = config.resolved_iterations(variant)
    n_coarse = min(max(int(round(coarse_fraction * iterations)), 1), iterations - 1)
    if n_coarse < 1:
        raise ValueError(f"config runs {iterations} iteration(s); coarse-to-fine needs at least 2")

    # the coarse stage: shrunk inputs, the first n_coarse iterations of the schedule, no auto-stop
    small = _downsample_depth(depth, scale)
    h, w = small.shape
    coarse_config = config.replace(iterations=n_coarse, auto_stop=False,
                                   lr_milestones=tuple(m for m in config.lr_milestones if m < n_coarse))
    coarse_noise = make_noise(config.noise_channels, h, w, seed=config.seed)
    coarse = _complete_depth(
        _downsample_image(rgb, scale) if rgb is not None else None, small,
        _downsample_camera(camera, scale) if camera is not None else None,
        [(_downsample_image(img, scale), _downsample_camera(cam, scale)) for img, cam in neighbors], variant,
        coarse_config, _downsample_depth(gt_depth, scale) if gt_depth is not None else None, transform,
        None, None, noise=coarse_noise)

    # the full-size stage: coarse weights, the same noise upsampled, the rest of the schedule
    passed = sum(1 for m in config.lr_milestones if m <= n_coarse)
    fine_config = config.replace(iterations=iterations - n_coarse, lr=config.lr * config.lr_gamma ** passed,
                                 lr_milestones=tuple(m - n_coarse for m in config.lr_milestones if m > n_coarse))
    fine_noise = torch.nn.functional.interpolate(coarse_noise, size=(h * scale, w * scale), mode="bilinear",
                                                 align_corners=False)[..., :H, :W].contiguous()
    fine = _complete_depth(rgb, depth, camera, neighbors, variant, fine_config, gt_depth, transform, None, coarse,
                           noise=fine_noise)

    history = {}
    for key in fine.history:
        a, b = coarse.history.get(key), fine.history[key]
        if key in ("eval_iteration", "lr_decay_iteration"):
            history[key] = np.concatenate([a, b + coarse.iterations])
        elif a is not None:
            history[key] = np.concatenate([a, b])
    history["eval_scale"] = np.concatenate([np.full(len(coarse.history["eval_iteration"]), scale),
                                            np.ones(len(fine.history["eval_iteration"]), int)])
    history["stage_iterations"] = np.array([coarse.iterations, fine.iterations])
    history["stage_seconds"] = np.array([coarse.seconds, fine.seconds])
    return dataclasses.replace(fine, history=history, iterations=coarse.iterations + fine.iterations,
                               best_iteration=coarse.iterations + fine.best_iteration,
                               seconds=coarse.seconds + fine.seconds)


def fit_image(image, mask=None, config: FitConfig | None = None, clean=None, callback=None) -> ImageResult:
    """Deep Image Prior on an image: fit ``image`` (H, W, 3) float [0, 1] where ``mask`` (H, W) bool
    is True (default: everywhere) with a masked MSE; ``clean`` (H, W, 3), if given, is tracked as PSNR.

    Denoising: pass the noisy image and no mask. Inpainting: pass the mask of known pixels.
    """
    config = FitConfig.for_profile(variant="rgbd") if config is None else config
    config.validate()
    image = _check_image(image, "image")
    H, W, _ = image.shape
    mask = np.ones((H, W), bool) if mask is None else np.asarray(mask)
    if mask.shape != (H, W) or mask.dtype != bool:
        raise ValueError(f"mask must be bool (H, W) = {(H, W)}, got {mask.dtype} {mask.shape}")
    if mask.sum() < MIN_VALID_PIXELS:
        raise ValueError(f"mask has {int(mask.sum())} known pixels; need at least {MIN_VALID_PIXELS}")
    clean = _check_image(clean, "clean", (H, W)) if clean is not None else None
    device = _device(config)
    heldout = _holdout_mask(mask, config.holdout_fraction, config.seed) if config.auto_stop else np.zeros_like(mask)
    target = _to_tensor(image, device)
    fit_mask = _to_tensor(mask & ~heldout, device)
    heldout_t = _to_tensor(heldout, device)
    n_fit = float(fit_mask.sum()) * 3

    def loss_fn(output):
        mse = (((output - target) ** 2) * fit_mask).sum() / n_fit
        return mse, {"mse": mse}

    heldout_error = None
    if heldout.any():
        def heldout_error(output):
            return float((((output - target) ** 2) * heldout_t).sum() / (float(heldout.sum()) * 3))

    evaluate = None
    if clean is not None:
        clean_t = _to_tensor(clean, device)

        def evaluate(output):
            mse = float(((output.clamp(0, 1) - clean_t) ** 2).mean())
            return {"psnr": 10.0 * np.log10(1.0 / max(mse, 1e-12))}

    user_callback = None
    if callback is not None:
        def user_callback(iteration, output):
            callback(iteration, output[0].permute(1, 2, 0).cpu().numpy())

    _check_memory(config, 3, H, W, 0, device)
    net, noise = _build(config, 3, H, W, device)
    start = time.perf_counter()
    output, history, ran, best = _run(net, noise, loss_fn, config, config.resolved_iterations("rgbd"),
                                      heldout_error, evaluate, user_callback, description="DIP")
    restored = output[0].permute(1, 2, 0).cpu().numpy().astype(np.float32)
    _check_finite_output("image", restored)
    return ImageResult(image=restored, history=history,
                       iterations=ran, best_iteration=best, seconds=time.perf_counter() - start)
