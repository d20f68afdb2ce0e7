"""Adam and its learning-rate schedules, as the loop (:mod:`ddp_lite.method.loop`) steps them.

    m ← β₁·m + (1 − β₁)·g,   v ← β₂·v + (1 − β₂)·g²,   θ ← θ − lr · (m / (1 − β₁ᵗ)) / (√(v / (1 − β₂ᵗ)) + ε)

One step is one call of torch's fused Adam kernel (``torch._fused_adam_``: every parameter updated in one
call, ~10–25 % faster per iteration on CPU than a loop over them, docs/studies/benchmark_history.md), the
very kernel ``torch.optim.Adam(fused=True)`` calls, with its defaults (β₁ 0.9, β₂ 0.999, ε 1e-8, no
weight decay): the same numbers to the bit (tests/method/test_adam.py holds them against it). What this
file leaves out is ``torch.optim``'s machinery: building a ``torch.optim`` optimizer imports
``torch._dynamo`` (the compiler, which no fit uses), ≈2 s of CPU in every process that fits, before the
first iteration: every notebook kernel, every ``ddp-lite complete``.

The schedules are torch's recursions too (``CosineAnnealingLR``, ``MultiStepLR``): each step's rate
comes from the last one, so a cut the stopper makes (``lr *= gamma``) carries on under the schedule.
"""
from __future__ import annotations

import math
from collections import Counter

import torch

__all__ = ["Adam", "CosineSchedule", "StepSchedule"]

FUSED_DEVICES = ("cpu", "cuda")  # elsewhere (mps, ...) torch.optim.Adam's loop over the parameters


class Adam:
    """Adam over ``params`` (tensors that require grad) at rate ``lr``, which the caller may change
    between steps. A parameter whose ``.grad`` is None is left as it is, its moments untouched.

    Example:
        >>> w = torch.nn.Parameter(torch.tensor([1.0, -2.0]))
        >>> adam = Adam([w], lr=0.1)
        >>> (w ** 2).sum().backward(); adam.step()
        >>> w.detach()  # the first step moves each weight by lr against the sign of its gradient
        tensor([ 0.9000, -1.9000])
    """

    def __init__(self, params, lr: float, betas=(0.9, 0.999), eps: float = 1e-8):
        self.params = list(params)
        self.lr = float(lr)
        self.betas, self.eps = (float(betas[0]), float(betas[1])), float(eps)
        self._moments = {}  # id(param) → (step (), m, v), made at the parameter's first step
        devices = {p.device.type for p in self.params}
        self._fallback = None
        if not devices <= set(FUSED_DEVICES):
            self._fallback = torch.optim.Adam(self.params, lr=self.lr, betas=self.betas, eps=self.eps)

    def zero_grad(self) -> None:
        """Drop every gradient (``set_to_none``): the next backward writes them afresh."""
        for p in self.params:
            p.grad = None

    @torch.no_grad()
    def step(self) -> None:
        """One Adam step of every parameter that has a gradient, at ``self.lr``."""
        if self._fallback is not None:
            self._fallback.param_groups[0]["lr"] = self.lr
            self._fallback.step()
            return
        params = [p for p in self.params if p.grad is not None]
        if not params:
            return
        for p in params:
            if id(p) not in self._moments:  # the step count as torch keeps it for the fused kernel: a float32 scalar
                self._moments[id(p)] = (torch.zeros((), dtype=torch.float32, device=p.device),
                                        torch.zeros_like(p, memory_format=torch.preserve_format),
                                        torch.zeros_like(p, memory_format=torch.preserve_format))
        steps, exp_avgs, exp_avg_sqs = zip(*(self._moments[id(p)] for p in params))
        torch._foreach_add_(list(steps), 1)
        torch._fused_adam_(params, [p.grad for p in params], list(exp_avgs), list(exp_avg_sqs), [], list(steps),
                           amsgrad=False, lr=self.lr, beta1=self.betas[0], beta2=self.betas[1], weight_decay=0.0,
                           eps=self.eps, maximize=False, grad_scale=None, found_inf=None)


class CosineSchedule:
    """The rate annealed from its start to 0 over ``iterations`` steps on a half cosine,
    lr_t = ½·lr₀·(1 + cos(π t / T)) for t ≤ T, by torch's ``CosineAnnealingLR`` recursion
    (its ``eta_min`` 0)."""

    def __init__(self, iterations: int):
        self.T, self.t, self.eta_min = int(iterations), 0, 0.0

    def next(self, lr: float) -> float:
        """The rate of the next step, from this step's ``lr``."""
        self.t += 1
        t, T = self.t, self.T
        ratio = (1 + math.cos(math.pi * t / T)) / (1 + math.cos(math.pi * (t - 1) / T))
        return ratio * (lr - self.eta_min) + self.eta_min


class StepSchedule:
    """The rate ×``gamma`` after each of the ``milestones`` (step counts, as torch's ``MultiStepLR``)."""

    def __init__(self, milestones, gamma: float):
        self.milestones, self.gamma, self.t = Counter(milestones), float(gamma), 0

    def next(self, lr: float) -> float:
        """The rate of the next step, from this step's ``lr``."""
        self.t += 1
        return lr * self.gamma ** self.milestones[self.t] if self.t in self.milestones else lr
