"""The optimisation loop shared by DDP and DIP: Adam on a loss of the net's output, top to bottom.

    θ* = argmin_θ L(f_θ(n)),   output* = f_θ*(n)          (Deep Image Prior, paper Eq. 1)

:func:`build` makes the net and its fixed input; :func:`run` fits it. What the loop leaves to
others: when to stop (:mod:`ddp_lite.method.stopping`), how long it will still take
(:mod:`ddp_lite.method.time_left`), whether the fit fits in memory (checked by the caller before
:func:`build`, :mod:`ddp_lite.method.runtime.memory`), and what is shown while it runs: the caller
passes a ``progress`` hook (:class:`ddp_lite.core.progress.FitProgress`), which the loop iterates
over and tells each held-out error and where its stopper now expects the fit to stop.
"""
from __future__ import annotations

import threading

import numpy as np
import torch

from ..core.progress import FitProgress
from .adam import Adam, CosineSchedule, StepSchedule
from .config import FitConfig
from .paper.nets import build_net, make_input
from .runtime.device import use_bf16
from .runtime.options import RunOptions
from .stopping import PlateauStopper
from .time_left import earliest_stop, expected_stop

__all__ = ["build", "run"]


# the seeded init below sets and draws from torch's one global generator: ensemble members
# built in parallel threads take turns
_INIT_LOCK = threading.Lock()


def build(config: FitConfig, out_channels: int, height: int, width: int, device, init_state=None, noise=None,
          extra=None):
    """The net and its fixed input (1, C, H, W): ``noise`` (made from the config when None), followed
    by the ``extra`` channels (1, C', H, W) when given (``kit.net_inputs.net_extras``)."""
    paper = config.paper
    in_channels = paper.noise_channels + (0 if extra is None else extra.shape[1])
    with _INIT_LOCK, torch.random.fork_rng(devices=[]):  # deterministic init without touching the caller's RNG
        torch.manual_seed(paper.seed)
        options = dict(down=paper.down, up=paper.up, pad=paper.pad) if paper.net == "unet" else {}
        net = build_net(paper.net, in_channels, out_channels, paper.channels, **options)
    if init_state is not None:
        try:
            net.load_state_dict(init_state)
        except RuntimeError as error:
            raise ValueError(f"init: its weights do not fit this config's network ({error.args[0].splitlines()[0]})")
    if noise is None:
        noise = make_input(config.net_inputs.base, paper.noise_channels, height, width, seed=paper.seed)
    elif tuple(noise.shape) != (1, paper.noise_channels, height, width):
        raise ValueError(f"noise must be (1, {paper.noise_channels}, {height}, {width}), got {tuple(noise.shape)}")
    if extra is not None:
        noise = torch.cat([noise.to(device), extra.to(device)], dim=1)  # (1, noise_channels + C', H, W)
    return net.to(device), noise.to(device)


def run(net, noise, loss_fn, config: FitConfig, iterations: int, held_out_error=None, evaluate=None,
        callback=None, *, progress: FitProgress, options: RunOptions):
    """Adam on ``loss_fn(net(noise))`` for at most ``iterations``; returns (kept output (1, C, H, W),
    history, iterations run, best iteration).

    ``loss_fn(output) -> (total, {name: term})``; ``held_out_error(output) -> float`` (None: no
    auto-stop), watched every ``config.stopping.eval_every`` iterations; ``evaluate(output) -> {name: float}``,
    tracked there too, never optimised; ``callback(iteration, output)`` every ``options.callback_every``;
    ``progress``: the caller's hook, iterated over for the iterations; ``options``: the run's memory format
    and callback rate (the net's precision is the config's)."""
    paper, stopping, tricks = config.paper, config.stopping, config.tricks
    adam = Adam(net.parameters(), lr=paper.lr)  # torch's fused Adam kernel, without torch.optim (adam.py says why)
    if paper.schedule == "cosine":
        schedule = CosineSchedule(iterations)
    else:
        schedule = StepSchedule([m for m in paper.lr_milestones if m < iterations], gamma=paper.lr_gamma)
    autocast = torch.autocast(noise.device.type, dtype=torch.bfloat16, enabled=use_bf16(config.precision.bf16, noise.device))
    if options.channels_last:
        net, noise = net.to(memory_format=torch.channels_last), noise.contiguous(memory_format=torch.channels_last)
    jitter = torch.Generator(device=noise.device).manual_seed(paper.seed + 1) if tricks.reg_noise_std else None
    terms_log = None  # (iterations, n_terms) kept on the device: no host read per iteration
    lrs = []
    evals = {"eval_iteration": [], "held_out": [], "lr_decay_iteration": []}
    averaged = best_output = None
    best_iteration = 0
    stop_check = stopping.auto_stop and held_out_error is not None
    stopper = PlateauStopper(stopping.patience, stopping.eval_every, stopping.plateau_decays)
    it = -1
    for it in progress:
        # one step: the net's output, the loss, Adam
        net_input = noise
        if jitter is not None:
            net_input = noise + tricks.reg_noise_std * torch.randn(noise.shape, generator=jitter, device=noise.device)
        with autocast:
            output = net(net_input)
        output = output.float().contiguous()
        total, terms = loss_fn(output)
        adam.zero_grad()
        total.backward()
        lrs.append(adam.lr)  # a Python float: no device sync
        adam.step()
        adam.lr = schedule.next(adam.lr)
        if terms_log is None:
            names = ["loss", *terms]
            terms_log = torch.zeros(iterations, len(names), device=noise.device)
        terms_log[it] = torch.stack([total.detach(), *(t.detach() for t in terms.values())])

        # the output this iteration offers (a running mean of the outputs, where the config asks for one)
        current = output.detach()
        if tricks.average_outputs:
            weight = tricks.average_outputs
            averaged = current if averaged is None else weight * averaged + (1 - weight) * current
            current = averaged

        # every eval_every iterations: score it; keep it if it is the best; cut the rate or stop on a plateau
        last = it + 1 == iterations
        if (it + 1) % stopping.eval_every == 0 or last:
            evals["eval_iteration"].append(it + 1)
            error = float(held_out_error(current)) if held_out_error is not None else float("nan")
            evals["held_out"].append(error)
            for key, value in (evaluate(current) if evaluate is not None else {}).items():
                evals.setdefault(key, []).append(value)
            if stop_check:
                event = stopper.update(error)
                if event == "improved":
                    best_iteration, best_output = it + 1, current.clone()
                elif event == "decay":
                    adam.lr *= paper.lr_gamma
                    evals["lr_decay_iteration"].append(it + 1)
                elif event == "stop":
                    break
                progress.held_out(error)
                progress.expect(expected_stop(stopper, it + 1, iterations), earliest_stop(stopper, it + 1, iterations))
        if callback is not None and options.callback_every and (it + 1) % options.callback_every == 0:
            callback(it + 1, current)
    progress.close()

    history = {name: column.cpu().numpy()[: it + 1] for name, column in zip(names, terms_log.T)}
    history["lr"] = np.asarray(lrs)
    history.update({key: np.asarray(values) for key, values in evals.items()})
    if best_output is None:  # no auto-stop: the last output is the one kept
        best_output, best_iteration = current, it + 1
    return best_output, history, it + 1, best_iteration
