"""PaperConfig: the paper's settings of one fit (supplement), each default the paper's.

The net and its fixed input, Adam's learning rate and schedule, the iteration count, the loss's
L1/SSIM shares and γ, the disparity range, and the seed. The kit's additions keep their settings
beside their code; :class:`~ddp_lite.method.config.FitConfig` holds this section with theirs.
"""
from __future__ import annotations

from dataclasses import dataclass

from ...core.checks import check_choice, check_int, check_int_tuple, check_real
from ...core.settings import Settings
from .nets import DOWNSAMPLINGS, NETS, PADDINGS, UPSAMPLINGS

__all__ = ["PaperConfig", "SCHEDULES", "MAX_ITERATIONS", "MAX_SEED"]

SCHEDULES = ("step", "cosine")
MAX_ITERATIONS = 1_000_000  # 60× the paper's 16000; more would only allocate (a loss history row per iteration)
MAX_SEED = 2**63 - 1  # seeds are signed 64-bit wherever torch and NumPy take them


@dataclass(frozen=True)
class PaperConfig(Settings):
    """The paper's settings (17 fields). ``iterations=None`` means 16000 (6000 for depth only);
    milestones are absolute iterations; ``gammas=None`` is the variant's (γ1, γ2)."""

    net: str = "unet"  # "unet" or "skip" (nets.py)
    channels: tuple | None = None  # encoder widths; None → the paper's
    down: str = "stride"  # UNet down-sampling: "stride" (DIP) or "pool" (Ronneberger)
    up: str = "bilinear"  # UNet up-sampling: "bilinear" or "nearest"
    pad: str = "reflect"  # UNet conv padding: "reflect" (DIP) or "zeros"
    noise_channels: int = 16  # channels of the fixed network input
    lr: float = 5e-5  # Adam's
    schedule: str = "step"  # "step" (lr × lr_gamma at each milestone) or "cosine" (to 0 at the last iteration)
    iterations: int | None = None
    lr_milestones: tuple = (12000, 15000)
    lr_gamma: float = 0.01
    lambda_z: float = 0.8  # L1 share of L_disp (Eq. 3)
    lambda_i: float = 0.5  # L1 share of L_rgb (Eq. 4)
    lambda_w: float = 0.5  # SSIM share of L_warp (Eq. 5)
    gammas: tuple | None = None  # (γ1, γ2) of Eq. 2; None → (0.96, 0.02) with warp, (0.98, 0.01) without
    disparity_margin: float = 1.25  # transform=None: d_min / margin … d_max × margin around the valid depth
    seed: int = 0  # the net's weights, its input noise, the held-out pixels

    def validate(self) -> None:
        check_choice(self.net, "config.net", NETS)
        if self.channels is not None:
            check_int_tuple(self.channels, "config.channels", minimum=1, min_length=2 if self.net == "unet" else 1)
        check_choice(self.down, "config.down", DOWNSAMPLINGS)
        check_choice(self.up, "config.up", UPSAMPLINGS)
        check_choice(self.pad, "config.pad", PADDINGS)
        check_choice(self.schedule, "config.schedule", SCHEDULES)
        check_int(self.noise_channels, "config.noise_channels", minimum=1)
        check_int(self.seed, "config.seed", minimum=0, maximum=MAX_SEED)
        if self.iterations is not None:
            check_int(self.iterations, "config.iterations", minimum=1, maximum=MAX_ITERATIONS)
        check_int_tuple(self.lr_milestones, "config.lr_milestones", minimum=1)
        check_real(self.lr, "config.lr", 0.0, low_open=True)
        check_real(self.lr_gamma, "config.lr_gamma", 0.0, low_open=True)
        for name in ("lambda_z", "lambda_i", "lambda_w"):
            check_real(getattr(self, name), f"config.{name}", 0.0, 1.0)
        check_real(self.disparity_margin, "config.disparity_margin", 1.0)
        if self.gammas is not None:
            if isinstance(self.gammas, (str, bytes)) or not isinstance(self.gammas, (tuple, list)) or len(self.gammas) != 2:
                raise TypeError(f"config.gammas must be a pair (γ1, γ2), got {self.gammas!r}")
            g1, g2 = (check_real(g, f"config.gammas[{i}]", 0.0, 1.0) for i, g in enumerate(self.gammas))
            if g1 + g2 > 1.0:
                raise ValueError(f"config.gammas must have γ1 + γ2 ≤ 1, got {self.gammas}")
