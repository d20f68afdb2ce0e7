"""The kit's net inputs (:class:`NetInputConfig`): the fixed input's base channels as the pixel coordinates
instead of noise (``base``, FitConfig's ``net_input``), and extra channels joined to them by the fit (off in the
``paper`` recipe): the view's colour image, blurred (``image_input``, :func:`image_channels`), and a classical
fill of the input disparity (``fill_input``). The net takes them as extra input channels; it does not know what
they are. ``fill_start`` starts the net's output at that fill instead (:func:`start_at`). A fit asks for the
channels and the start in one call, :func:`net_extras`.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import torch
import torch.nn.functional as F

from ...classical.depth_fills import fill_linear
from ...classical.guided_fills import fill_colorization
from ...core.checks import check_bool, check_choice, check_real
from ...core.settings import Settings
from ..paper.losses import blur_valid, gaussian_kernel_1d  # SSIM's separable Gaussian, reused for the image input
from ..paper.nets import NET_INPUTS
from ..runtime.tensors import to_tensor

__all__ = ["NetInputConfig", "net_extras", "image_channels", "start_at"]


@dataclass(frozen=True)
class NetInputConfig(Settings):
    """What the net is fed besides the paper's noise, and where its output starts (5 fields; the defaults
    are the paper's). ``base`` is FitConfig's ``net_input`` (``flat_names``)."""

    section = "net_inputs"
    flat_names = {"base": "net_input"}

    # the channels every fit's input starts with, the paper's noise_channels of them, before any image or fill
    # channels are joined: "noise" (the paper) or "meshgrid" (x, y in the first two, noise in the rest; nets.make_input)
    base: str = "noise"
    image_input: float = 0.0  # > 0: the colour image × this joins the net input (variants with colour)
    image_blur: float = 1.0  # σ in px of the Gaussian blur on that image (0: none)
    fill_input: float = 0.0  # > 0: a classical fill of the input disparity × this joins the net input
    fill_start: bool = False  # the net's first output is that fill: it fits what the fill gets wrong (start_at)

    def validate(self) -> None:
        check_choice(self.base, "config.net_input", NET_INPUTS)
        for name in ("image_input", "image_blur", "fill_input"):
            check_real(getattr(self, name), f"config.{name}", 0.0)
        check_bool(self.fill_start, "config.fill_start")

    def describe(self, noise_channels: int = 16) -> str:
        """These inputs' part of a recipe's one-line description (``kit.recipes.describe_method``), with the
        paper's ``noise_channels`` beside them; "" for the paper's input."""
        parts = ["the pixel coordinates" + (" + noise" if noise_channels > 2 else "")
                 if self.base == "meshgrid" else "noise"]
        if self.image_input:
            parts.append(f"the colour image (blurred, σ {self.image_blur:g} px; not for depth-only)")
        return ", net input: " + " + ".join(parts) if parts != ["noise"] else ""

    def equation(self, noise_channels: int, uses_rgb: bool) -> tuple[list[str], list[str]]:
        """(the paper's inputs that stay, the kit's added ones) of the net in the equation a config optimises
        (``method.equation``), LaTeX, with the paper's ``noise_channels``, for a variant that sees colour or not."""
        in_paper = ["\\text{noise}"] if self.base != "meshgrid" or noise_channels > 2 else []
        added = ["u, v"] if self.base == "meshgrid" else []
        if uses_rgb and self.image_input > 0:
            added.append(f"G_{{{self.image_blur:g}}} * I_{{\\mathrm{{in}}}}")
        if self.fill_input > 0:
            added.append("\\text{fill}(Z_{\\mathrm{in}})")
        return in_paper, added


def net_extras(config: NetInputConfig, rgb_t: torch.Tensor | None, rgb: np.ndarray | None, disparity: np.ndarray,
               device) -> tuple[torch.Tensor | None, torch.Tensor | None]:
    """What ``config`` adds to one fit's net: ``(channels, start)``, each None where it adds nothing.

    ``channels`` (1, C, H, W): the extra input channels joined to the paper's input, in this order: the
    colour image (:func:`image_channels` of ``rgb_t`` (1, 3, H, W); None: a variant that does not see
    colour) and ``fill_input ×`` the fill. ``start`` (1, 1, H, W), with ``fill_start``: the disparity the
    net's depth output starts at (:func:`start_at`), the fill itself.

    The fill is a classical fill of ``disparity`` (H, W) in [0, 1], NaN where the fit has no input (holes
    and held-out pixels): its colorization fill (``guided_fills.fill_colorization``) guided by ``rgb``
    (H, W, 3), or its linear fill without colour (``rgb`` None). From this input the net starts close to
    a fill that already follows the colour, and its prior has to explain only what that fill gets wrong;
    from the coordinates and the image alone, a hole's depth is whatever function of them fits the valid
    pixels best.

    Example:
        >>> disparity = np.array([[0.2, np.nan, 0.6], [0.2, 0.4, 0.6]])
        >>> channels, start = net_extras(NetInputConfig(fill_input=2.0), None, None, disparity, "cpu")
        >>> tuple(channels.shape), start  # no colour channels without rgb_t, no start without fill_start
        ((1, 1, 2, 3), None)
        >>> [[round(v, 3) for v in row] for row in channels[0, 0].tolist()]  # the linear fill × 2
        [[0.4, 0.8, 1.2], [0.4, 0.8, 1.2]]
    """
    channels = []
    if config.image_input > 0 and rgb_t is not None:
        channels.append(image_channels(rgb_t, config.image_input, config.image_blur))  # (1, 3, H, W)
    fill = None
    if config.fill_input > 0 or config.fill_start:
        shifted = disparity + 1.0  # the fills take positive values (written for metres); 0 is a valid disparity
        filled = fill_colorization(shifted, rgb) if rgb is not None else fill_linear(shifted)
        fill = to_tensor(filled - 1.0, device)  # (1, 1, H, W) in [0, 1]
    if config.fill_input > 0:
        channels.append(config.fill_input * fill)
    return (torch.cat(channels, dim=1) if channels else None), (fill if config.fill_start else None)


def image_channels(image: torch.Tensor, scale: float = 1.0, blur: float = 1.0) -> torch.Tensor:
    """The colour image as extra input channels: ``scale ×`` ``image`` (1, 3, H, W) in [0, 1],
    Gaussian-blurred with σ = ``blur`` px (kernel radius round(3σ); the border pixel repeated;
    ``blur=0``: not blurred). Same shape as ``image``.

    With the view's colours in its input the net can put depth edges exactly where the colour
    edges are, which a function of the coordinates alone draws blurred. The blur keeps fine
    texture (grass, bark) out: inside a hole, whatever the input varies with, the output can too.

    Example:
        >>> step = torch.zeros(1, 3, 1, 6); step[..., 3:] = 1.0  # a colour edge between pixels 2 and 3
        >>> [round(v, 3) for v in image_channels(step, 1.0, 1.0)[0, 0, 0].tolist()]
        [0.004, 0.058, 0.3, 0.7, 0.942, 0.996]
    """
    if blur > 0:
        radius = int(3 * blur + 0.5)
        kernel = gaussian_kernel_1d(2 * radius + 1, float(blur), image.dtype, str(image.device))  # (2r + 1,)
        image = blur_valid(F.pad(image, (radius,) * 4, mode="replicate"), kernel)  # (1, 3, H, W)
    return scale * image


def start_at(net, disparity: torch.Tensor) -> None:
    """Make ``net``'s first output channel start at ``disparity`` (1, 1, H, W) in [0, 1] and learn a
    correction to it: that channel's weights and bias in the net's 1×1 ``head`` are zeroed, so its
    logits start at 0 everywhere, and logit(disparity) (clipped to [1e-4, 1 − 1e-4]) is added before the
    sigmoid as a fixed offset (``net.start_offset``, (1, C_out, H, W), 0 on the other channels, which
    keep their random start).

    The fit then starts where a classical fill is, and the deep prior shapes what it changes: the
    correction is what the net's output is, smooth the way that output would be, and 0 where the
    losses do not move it.

    Example:
        >>> from ddp_lite.method.paper.nets import UNet
        >>> net, x = UNet(2, 4, channels=(4, 8)), torch.rand(1, 2, 6, 8)
        >>> start_at(net, torch.full((1, 1, 6, 8), 0.3))
        >>> depth_channel = net(x)[0, 0]
        >>> round(float(depth_channel.min()), 4), round(float(depth_channel.max()), 4)
        (0.3, 0.3)
    """
    with torch.no_grad():
        net.head.weight[:1].zero_()
        net.head.bias[:1].zero_()
    offset = torch.zeros(1, net.head.out_channels, *disparity.shape[-2:], device=disparity.device)
    offset[:, :1] = torch.logit(disparity.float().clamp(1e-4, 1 - 1e-4))
    net.start_offset = offset
