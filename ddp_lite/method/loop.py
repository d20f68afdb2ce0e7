"""The optimisation loop shared by DDP and DIP, its ground-truth-free stopping, and its memory guard.

    θ* = argmin_θ L(f_θ(n)),   output* = f_θ*(n)          (Deep Image Prior, paper Eq. 1)

Stopping: a run either follows a fixed schedule (the paper's) or stops by itself. For the
latter a small random share of the *valid* pixels is held out of the loss (:func:`holdout_mask`);
their error is a ground-truth-free estimate of how well the net predicts depth it has not seen.
The output at the best held-out error is kept. When it has not improved for ``patience``
iterations (a plateau) the learning rate is cut by ``lr_gamma``, ``plateau_decays`` times, and the
run stops at the next plateau (:class:`PlateauStopper`). Cutting the rate matters: at a constant
rate the hole error jumps ±10 % between evaluations, and stopping on that noise gave away 13 % on
average against the best a long run reached (``benchmarks/bench_autostop.py``).
"""
from __future__ import annotations

import os
import threading

import numpy as np
import torch
from scipy import ndimage

from .config import FitConfig
from .runtime.device import use_bf16
from .runtime.tensors import to_tensor
from .paper.nets import SKIP_CHANNELS, UNET_CHANNELS, build_net, count_parameters, make_input
from ..core.progress import progress as tqdm

__all__ = ["PlateauStopper", "EXPECTED_STOP_SHARE", "EARLIEST_STOP_SHARE", "RUN_AFTER_CUT_SHARE", "expected_share", "earliest_share", "run", "build", "holdout_mask", "estimate_peak_memory_gb", "check_memory",
           "check_finite_output", "memory_limit_gb", "heldout_error_fn", "hole_errors_fn"]


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
        self.patience, self.eval_every, self.decays_left, self.decays = patience, eval_every, decays, decays
        self.best, self.since_best = float("inf"), 0
        self.since_cut = None  # iterations since the last cut (None before the first)

    def update(self, error: float) -> str:
        """Feed one held-out error; returns ``"improved"``, ``"decay"``, ``"stop"`` or ``""``."""
        if self.since_cut is not None:
            self.since_cut += self.eval_every
        if error < self.best:
            self.best, self.since_best = error, 0
            return "improved"
        self.since_best += self.eval_every
        if self.since_best < self.patience:
            return ""
        if self.decays_left > 0:
            self.decays_left -= 1
            self.since_best, self.since_cut = 0, 0
            return "decay"
        return "stop"

    def earliest_stop(self, done: int, cap: int) -> int:
        """The earliest iteration this run can stop at, ``done`` of ``cap`` run: the plateaus still to come,
        none of them broken by a new best."""
        return min(cap, done + max(0, self.patience - self.since_best) + self.decays_left * self.patience)

    def expected_stop(self, done: int, cap: int) -> int:
        """The iteration this run is expected to stop at, ``done`` of ``cap`` run: a cut's iteration plus
        the run fits usually go on for after it (:data:`RUN_AFTER_CUT_SHARE` of the cap), the last cut's
        once it has come, else the earliest the first can come; before the first cut, at least the share
        auto-stopped fits usually run (:data:`EXPECTED_STOP_SHARE`); never before the plateaus still to
        come (:meth:`earliest_stop`), never past ``cap``. Without cuts (``decays=0``): at least that share."""
        at_least = self.earliest_stop(done, cap)
        run_on = round(RUN_AFTER_CUT_SHARE * cap)
        if self.since_cut is not None:
            return min(cap, max(at_least, done - self.since_cut + run_on))
        expected = max(at_least, round(EXPECTED_STOP_SHARE * cap))
        if self.decays_left > 0:  # a cut to come (with none, the next plateau is the stop)
            expected = max(expected, done + max(0, self.patience - self.since_best) + run_on)
        return min(cap, expected)


# Where `class`'s auto-stopped fits stop, as a share of their cap: of 3,771 fits in
# benchmarks/results/quality_class*.jsonl the median stopped at 490 of 600, one in twenty before 320,
# a quarter ran to the cap. After the learning-rate cut a fit goes on improving for a while at the lower
# rate: of 54 `class` fits (the 22 rendered and 5 real cases of bench_quality.py, rgbd seed 0 and
# rgbd+warp seed 1, held to AVX2) the 53 that cut stopped 80-360 iterations after the cut (median 220),
# where the next plateau could have ended them 50 after (benchmarks/study_time_left.py). Only the
# time-left estimate uses these.
EXPECTED_STOP_SHARE = 0.8
EARLIEST_STOP_SHARE = 0.55
RUN_AFTER_CUT_SHARE = 0.4  # 240 of 600: the cut's iteration plus this share of the cap, where such fits stopped


def expected_share(config: FitConfig) -> float:
    """The share of its iterations a fit of ``config`` is expected to run (1 without auto-stop)."""
    return EXPECTED_STOP_SHARE if config.auto_stop else 1.0


def earliest_share(config: FitConfig) -> float:
    """The share of its iterations a fit of ``config`` runs at least, bar one in twenty (1 without auto-stop)."""
    return EARLIEST_STOP_SHARE if config.auto_stop else 1.0


def run(net, noise, loss_fn, config: FitConfig, iterations: int, heldout_error=None, evaluate=None,
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
                if hasattr(bar, "expect"):  # a command's clock: its time left follows the stopper
                    bar.expect(stopper.expected_stop(it + 1, iterations), stopper.earliest_stop(it + 1, iterations))
        if callback is not None and config.callback_every and (it + 1) % config.callback_every == 0:
            callback(it + 1, current)
    bar.close()
    history = {name: column.cpu().numpy()[: it + 1] for name, column in zip(names, terms_log.T)}
    history["lr"] = np.asarray(lrs)
    history.update({key: np.asarray(values) for key, values in evals.items()})
    if best_output is None:
        best_output, best_iteration = current, it + 1
    return best_output, history, it + 1, best_iteration


# the seeded init below sets and draws from torch's one global generator: ensemble members
# built in parallel threads take turns
_INIT_LOCK = threading.Lock()


def build(config: FitConfig, out_channels: int, height: int, width: int, device, init_state=None, noise=None,
          image=None):
    """The net and its fixed input (1, C, H, W): ``noise`` (made from the config when None), followed
    by ``image`` (1, 3, H, W) when given (``kit.net_inputs.image_channels``)."""
    in_channels = config.noise_channels + (0 if image is None else image.shape[1])
    with _INIT_LOCK, torch.random.fork_rng(devices=[]):  # deterministic init without touching the caller's RNG
        torch.manual_seed(config.seed)
        options = dict(down=config.down, up=config.up, pad=config.pad) if config.net == "unet" else {}
        net = build_net(config.net, in_channels, out_channels, config.channels, **options)
    if init_state is not None:
        try:
            net.load_state_dict(init_state)
        except RuntimeError as error:
            raise ValueError(f"init: its weights do not fit this config's network ({error.args[0].splitlines()[0]})")
    if noise is None:
        noise = make_input(config.net_input, config.noise_channels, height, width, seed=config.seed)
    elif tuple(noise.shape) != (1, config.noise_channels, height, width):
        raise ValueError(f"noise must be (1, {config.noise_channels}, {height}, {width}), got {tuple(noise.shape)}")
    if image is not None:
        noise = torch.cat([noise.to(device), image.to(device)], dim=1)  # (1, noise_channels + 3, H, W)
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
    in_channels = config.noise_channels + (3 if config.image_input > 0 else 0) + (1 if config.fill_input > 0 else 0)
    units = in_channels + sum(c / 4 ** (k + first) for k, c in enumerate(channels))
    with torch.device("meta"):
        parameters = count_parameters(build_net(config.net, in_channels, out_channels, config.channels))
    activations = 4.0 * pixels * (FLOATS_PER_UNIT * units + FLOATS_PER_NEIGHBOR_PIXEL * n_neighbors)
    return MEMORY_BASE_GB + (activations + BYTES_PER_PARAMETER * parameters) / 2 ** 30


def memory_limit_gb(config: FitConfig, device: torch.device) -> tuple[float | None, str]:
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


def check_memory(config: FitConfig, out_channels: int, height: int, width: int, n_neighbors: int, device) -> None:
    """Refuse, before the net is built, a fit whose estimated peak exceeds the limit."""
    limit, source = memory_limit_gb(config, device)
    if limit is None:
        return
    estimate = estimate_peak_memory_gb(config, out_channels, height, width, n_neighbors)
    if estimate > limit:
        raise ValueError(
            f"depth: a {height}×{width} (H×W) fit with this config needs about {estimate:.1f} GB at its peak, more than "
            f"the limit of {limit:.1f} GB ({source}). Downscale the inputs (e.g. cv2.resize, or "
            f"datasets.resize_scene for a Scene), use smaller config.channels, or a GPU; or raise the limit with "
            f"config.max_memory_gb (CLI: --max-memory-gb) if you know it fits.")


def check_finite_output(name: str, array) -> None:
    """A fit must never return NaN or inf: raise instead (the optimisation diverged)."""
    if array is not None and not np.all(np.isfinite(array)):
        bad = int(np.size(array) - np.isfinite(array).sum())
        raise FloatingPointError(f"the fit's {name} has {bad} non-finite value(s) of {np.size(array)}: the "
                                 f"optimisation diverged. Lower config.lr, or check the inputs and init.")


def heldout_error_fn(target: torch.Tensor, heldout: np.ndarray, device):
    """``error(output)``: the mean |Z_out - Z_in| over the held-out pixels (H, W) bool, the
    ground-truth-free score auto-stop watches; ``target`` (1, 1, H, W) is Z_in."""
    n_heldout = float(heldout.sum())
    heldout_t = to_tensor(heldout, device).bool()

    def heldout_error(output):
        return float(((output[:, :1] - target).abs() * heldout_t).sum() / n_heldout)
    return heldout_error


def hole_errors_fn(gt_depth: np.ndarray, valid: np.ndarray, transform, device):
    """``errors(output)`` → {"hole_rmse": disparity RMSE, "hole_rmse_m": depth RMSE in metres} over the
    holes (``valid`` False) where ``gt_depth`` (H, W) metres is known: tracked, never optimised."""
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
    return evaluate


def holdout_mask(valid: np.ndarray, fraction: float, seed: int, shape: str = "pixels") -> np.ndarray:
    """A random share ``fraction`` of the valid pixels (H, W) bool, seeded: scattered single pixels, or
    ``"blobs"`` (smooth random blobs, blur scale min(H, W)/24 px, like the holes a fit must fill: a
    single held-out pixel is predicted from its neighbours by any smooth fit, a blob is not)."""
    rng = np.random.default_rng(seed + 12345)
    if shape == "pixels":
        return valid & (rng.random(valid.shape) < fraction)
    H, W = valid.shape
    field = ndimage.gaussian_filter(rng.standard_normal((H, W)), max(1.0, min(H, W) / 24.0), mode="wrap")
    return valid & (field <= np.quantile(field[valid], fraction))
