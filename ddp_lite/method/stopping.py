"""Ground-truth-free stopping: the valid pixels held out of the loss, their error, and the plateau rule.

A run either follows a fixed schedule (the paper's) or stops by itself. For the latter a small
random share of the *valid* pixels is held out of the loss (:func:`held_out_mask`); their error
(:func:`held_out_error_fn`) is a ground-truth-free estimate of how well the net predicts depth it has
not seen. The output at the best held-out error is kept. When it has not improved for ``patience``
iterations (a plateau) the learning rate is cut by ``lr_gamma``, ``plateau_decays`` times, and the
run stops at the next plateau (:class:`PlateauStopper`). Cutting the rate matters: at a constant
rate the hole error jumps between evaluations, and stopping on that noise gave away much of what a long
run reached (``docs/studies/benchmark_history.md``, "bench_autostop.py: the stop rule of the `class`
profile"). Its settings are :class:`StoppingConfig`.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import torch
from scipy import ndimage

from ..core.checks import check_bool, check_choice, check_int, check_real
from ..core.settings import Settings
from .runtime.tensors import to_tensor

__all__ = ["StoppingConfig", "HELD_OUT_SHAPES", "PlateauStopper", "held_out_mask", "held_out_error_fn"]

HELD_OUT_SHAPES = ("pixels", "blobs")


@dataclass(frozen=True)
class StoppingConfig(Settings):
    """When a fit stops before its iterations (6 fields; off by default, the paper's fixed schedule)."""

    auto_stop: bool = False
    held_out_fraction: float = 0.05  # share of valid pixels held out when auto_stop is on
    held_out_shape: str = "pixels"  # their shape: "pixels" (scattered) or "blobs" (hole-like patches)
    patience: int = 200  # iterations without held-out improvement that make a plateau
    plateau_decays: int = 0  # cut lr by lr_gamma at the first this-many plateaus, stop at the next
    eval_every: int = 10  # iterations between held-out (and hole) errors

    def validate(self) -> None:
        check_bool(self.auto_stop, "config.auto_stop")
        check_choice(self.held_out_shape, "config.held_out_shape", HELD_OUT_SHAPES)
        check_real(self.held_out_fraction, "config.held_out_fraction", 0.0, 0.5, low_open=True, high_open=True)
        check_int(self.patience, "config.patience", minimum=1)
        check_int(self.plateau_decays, "config.plateau_decays", minimum=0)
        check_int(self.eval_every, "config.eval_every", minimum=1)


class PlateauStopper:
    """Ground-truth-free stopping on a held-out error, checked every ``eval_every`` iterations.

    A *plateau* is ``patience`` iterations without a new best held-out error. At each of the
    first ``decays`` plateaus the learning rate is cut (``"decay"``) and the count restarts; at
    the next one the run stops (``"stop"``). With ``decays=0`` this is plain early stopping.
    The caller keeps the output of the best evaluation (``improved``). Where the run is then
    expected to stop is :mod:`ddp_lite.method.time_left`'s to say.

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


def held_out_mask(valid: np.ndarray, fraction: float, seed: int, shape: str = "pixels") -> np.ndarray:
    """A random share ``fraction`` of the valid pixels (H, W) bool, seeded: scattered single pixels, or
    ``"blobs"`` (smooth random blobs, blur scale min(H, W)/24 px, like the holes a fit must fill: a
    single held-out pixel is predicted from its neighbours by any smooth fit, a blob is not)."""
    rng = np.random.default_rng(seed + 12345)
    if shape == "pixels":
        return valid & (rng.random(valid.shape) < fraction)
    H, W = valid.shape
    field = ndimage.gaussian_filter(rng.standard_normal((H, W)), max(1.0, min(H, W) / 24.0), mode="wrap")
    return valid & (field <= np.quantile(field[valid], fraction))


def held_out_error_fn(target: torch.Tensor, held_out: np.ndarray, device):
    """``error(output)``: the mean |Z_out - Z_in| over the held-out pixels (H, W) bool, the
    ground-truth-free score auto-stop watches; ``target`` (1, 1, H, W) is Z_in."""
    n_held_out = float(held_out.sum())
    held_out_t = to_tensor(held_out, device).bool()

    def held_out_error(output):
        return float(((output[:, :1] - target).abs() * held_out_t).sum() / n_held_out)
    return held_out_error
