"""Deep Image Prior's two per-iteration tricks (Ulyanov et al. 2018), off in the paper: input jitter
and output averaging. The loop (:func:`ddp_lite.method.loop.run`) applies them:

    net input at iteration t:   n + σ·N(0, 1)                 (reg_noise_std σ, fresh noise each time)
    output offered at t:        a·y_{t-1} + (1 − a)·f_θ(·)    (average_outputs a, an EMA of the outputs)
"""
from __future__ import annotations

from dataclasses import dataclass

from ..core.checks import check_real
from ..core.settings import Settings

__all__ = ["DipTricks"]


@dataclass(frozen=True)
class DipTricks(Settings):
    """DIP's per-iteration tricks (2 fields; 0: off, the paper)."""

    reg_noise_std: float = 0.0  # input jitter σ (1/30 in DIP)
    average_outputs: float = 0.0  # EMA weight a of the outputs (0.99 in DIP)

    def validate(self) -> None:
        check_real(self.reg_noise_std, "config.reg_noise_std", 0.0)
        check_real(self.average_outputs, "config.average_outputs", 0.0, 1.0, high_open=True)
