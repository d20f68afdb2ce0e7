"""The generators: a UNet (the paper's choice) and Deep Image Prior's SkipNet.

Both map a fixed input tensor (B, C_in, H, W) to an output (B, C_out, H, W) in [0, 1] (sigmoid):
16 channels of uniform noise, as in the paper, or the pixel coordinates, alone or followed by
noise channels (``make_input``; Deep Image Prior's input for large holes); optionally followed by
extra input channels the caller gives (the kit's colour image and classical fill:
:mod:`ddp_lite.method.kit.net_inputs`).
Nothing is pretrained: the architecture itself is the prior. Each network pads its input to a
multiple of its total down-sampling factor (reflection padding) and crops the output back, so
any image size works.
"""
from __future__ import annotations

import numpy as np
import torch
import torch.nn as nn
import torch.nn.functional as F


__all__ = ["UNet", "SkipNet", "make_noise", "make_input", "build_net", "count_parameters"]

UNET_CHANNELS = (32, 64, 128, 256, 512)  # the paper's encoder
SKIP_CHANNELS = (128, 128, 128, 128, 128)  # DIP's inpainting "skip" net
SKIP_SKIP_CHANNELS = (4, 4, 4, 4, 4)


def make_noise(channels: int, height: int, width: int, seed: int = 0, scale: float = 0.1) -> torch.Tensor:
    """The fixed network input (1, channels, H, W): uniform noise in [0, scale), as DIP uses."""
    generator = torch.Generator().manual_seed(seed)
    return torch.rand(1, channels, height, width, generator=generator) * scale


NET_INPUTS = ("noise", "meshgrid")


def make_input(kind: str, channels: int, height: int, width: int, seed: int = 0) -> torch.Tensor:
    """The fixed network input (1, channels, H, W) of a fit.

    - ``"noise"`` (the paper's): :func:`make_noise`, uniform noise in [0, 0.1);
    - ``"meshgrid"``: channel 0 is the column x / (W − 1) and channel 1 the row y / (H − 1), both in
      [0, 1] with pixel (0, 0) at the top left, and the other ``channels − 2`` are
      ``make_noise(channels − 2, ...)``. DIP feeds such a coordinate grid for large holes: the net
      starts out as a smooth function of position, so a hole far from valid pixels, above all one
      at the image border, is continued smoothly instead of from the noise under it.

    Example:
        >>> grid = make_input("meshgrid", 3, 2, 5)
        >>> grid[0, 0, 0].tolist(), grid[0, 1, :, 0].tolist()
        ([0.0, 0.25, 0.5, 0.75, 1.0], [0.0, 1.0])
    """
    if kind == "noise":
        return make_noise(channels, height, width, seed=seed)
    if kind != "meshgrid":
        raise ValueError(f"kind must be one of {NET_INPUTS}, got {kind!r}")
    if channels < 2:
        raise ValueError(f"a meshgrid input needs at least 2 channels, got {channels}")
    x, y = torch.linspace(0.0, 1.0, width), torch.linspace(0.0, 1.0, height)  # one pixel: [0.]
    grid = torch.stack(torch.meshgrid(x, y, indexing="xy"))[None]  # (1, 2, H, W): x, then y
    return torch.cat([grid, make_noise(channels - 2, height, width, seed=seed)], dim=1)


PADDINGS = ("reflect", "zeros")
DOWNSAMPLINGS = ("stride", "pool")
UPSAMPLINGS = ("bilinear", "nearest")
NETS = ("unet", "skip")


def _conv(c_in: int, c_out: int, kernel: int = 3, stride: int = 1, pad: str = "reflect") -> nn.Sequential:
    """Conv → BatchNorm → LeakyReLU(0.2): DIP's basic block. ``pad="reflect"`` is DIP's border;
    ``"zeros"`` lets the convolution pad by itself (one op less per layer)."""
    reflect = pad == "reflect" and kernel > 1
    return nn.Sequential(
        nn.ReflectionPad2d(kernel // 2) if reflect else nn.Identity(),
        nn.Conv2d(c_in, c_out, kernel, stride=stride, padding=0 if reflect else kernel // 2, bias=False),
        nn.BatchNorm2d(c_out),
        nn.LeakyReLU(0.2),
    )


class _PadCrop(nn.Module):
    """Pads (B, C, H, W) to a multiple of ``factor`` before the body and crops after. ``start_offset``
    (None, or (1, C_out, H, W), fixed) is added before the sigmoid: the kit's start at a classical fill
    (:func:`ddp_lite.method.kit.net_inputs.start_at`); the paper's nets have none."""

    factor = 1
    start_offset = None

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        H, W = x.shape[-2:]
        pad_h, pad_w = (-H) % self.factor, (-W) % self.factor
        if pad_h or pad_w:
            mode = "reflect" if pad_h < H and pad_w < W else "replicate"
            x = F.pad(x, (0, pad_w, 0, pad_h), mode=mode)
        logits = self.body(x)[..., :H, :W]  # (B, C_out, H, W)
        if self.start_offset is not None:
            logits = logits + self.start_offset
        return torch.sigmoid(logits)


class UNet(_PadCrop):
    """Encoder-decoder with skip connections; 3×3 convs; encoder widths ``channels``.

    ``down``: ``"stride"`` (a stride-2 conv, DIP's choice) or ``"pool"`` (2×2 max-pool then a conv,
    Ronneberger's UNet, which the paper cites); ``up``: ``"bilinear"`` or ``"nearest"``
    up-sampling in the decoder; ``pad``: ``"reflect"`` or ``"zeros"`` at every 3×3 conv.

    Example:
        >>> net = UNet(16, 4, channels=(8, 16, 32))
        >>> net(torch.rand(1, 16, 30, 41)).shape
        torch.Size([1, 4, 30, 41])
    """

    def __init__(self, in_channels: int = 16, out_channels: int = 4, channels=UNET_CHANNELS, down: str = "stride",
                 up: str = "bilinear", pad: str = "reflect"):
        super().__init__()
        channels = tuple(int(c) for c in channels)
        if len(channels) < 2 or min(channels) < 1:
            raise ValueError(f"channels must list at least two positive widths, got {channels}")
        for name, value, allowed in (("down", down, DOWNSAMPLINGS), ("up", up, UPSAMPLINGS), ("pad", pad, PADDINGS)):
            if value not in allowed:
                raise ValueError(f"{name} must be one of {allowed}, got {value!r}")
        self.factor = 2 ** (len(channels) - 1)
        self.up_mode = up
        self.inc = nn.Sequential(_conv(in_channels, channels[0], pad=pad), _conv(channels[0], channels[0], pad=pad))

        def down_block(c_in, c_out):
            first = [nn.MaxPool2d(2), _conv(c_in, c_out, pad=pad)] if down == "pool" else [_conv(c_in, c_out, stride=2, pad=pad)]
            return nn.Sequential(*first, _conv(c_out, c_out, pad=pad))

        self.downs = nn.ModuleList(down_block(c_in, c_out) for c_in, c_out in zip(channels[:-1], channels[1:]))
        self.ups = nn.ModuleList(
            nn.Sequential(_conv(c_deep + c_skip, c_skip, pad=pad), _conv(c_skip, c_skip, pad=pad))
            for c_deep, c_skip in zip(channels[:0:-1], channels[-2::-1]))
        self.head = nn.Conv2d(channels[0], out_channels, 1)

    def body(self, x: torch.Tensor) -> torch.Tensor:
        skips = [self.inc(x)]  # (B, c0, H, W)
        for down in self.downs:
            skips.append(down(skips[-1]))  # (B, c_k, H / 2^k, W / 2^k)
        x = skips.pop()
        for up in self.ups:
            skip = skips.pop()
            x = F.interpolate(x, size=skip.shape[-2:], mode=self.up_mode,
                              **({"align_corners": False} if self.up_mode == "bilinear" else {}))
            x = up(torch.cat([x, skip], dim=1))
        return self.head(x)


class SkipNet(_PadCrop):
    """Deep Image Prior's "skip" architecture: strided-conv encoder, bilinear-upsampling decoder,
    thin 1×1 skip branches concatenated at every scale.

    Example:
        >>> SkipNet(16, 4, channels=(8, 8), skip_channels=(2, 2))(torch.rand(1, 16, 20, 20)).shape
        torch.Size([1, 4, 20, 20])
    """

    def __init__(self, in_channels: int = 16, out_channels: int = 4, channels=SKIP_CHANNELS,
                 skip_channels=SKIP_SKIP_CHANNELS):
        super().__init__()
        channels, skip_channels = tuple(channels), tuple(skip_channels)
        if len(channels) != len(skip_channels) or len(channels) < 1:
            raise ValueError(f"channels and skip_channels must have the same non-zero length, "
                             f"got {channels} and {skip_channels}")
        self.factor = 2 ** len(channels)
        self.levels = nn.ModuleList()
        c_in = in_channels
        for depth, (c, c_skip) in enumerate(zip(channels, skip_channels)):
            c_deeper = channels[depth + 1] if depth + 1 < len(channels) else 0
            self.levels.append(nn.ModuleDict({
                "skip": _conv(c_in, c_skip, kernel=1) if c_skip else nn.Identity(),
                "down": nn.Sequential(_conv(c_in, c, stride=2), _conv(c, c)),
                "up": nn.Sequential(nn.BatchNorm2d(c_skip + (c_deeper or c)), _conv(c_skip + (c_deeper or c), c),
                                    _conv(c, c, kernel=1)),
            }))
            c_in = c
        self.head = nn.Conv2d(channels[0], out_channels, 1)

    def _level(self, x: torch.Tensor, depth: int) -> torch.Tensor:
        level = self.levels[depth]
        deeper = level["down"](x)  # (B, c, H/2, W/2)
        if depth + 1 < len(self.levels):
            deeper = self._level(deeper, depth + 1)
        deeper = F.interpolate(deeper, size=x.shape[-2:], mode="bilinear", align_corners=False)
        parts = [level["skip"](x), deeper] if not isinstance(level["skip"], nn.Identity) else [deeper]
        return level["up"](torch.cat(parts, dim=1))

    def body(self, x: torch.Tensor) -> torch.Tensor:
        return self.head(self._level(x, 0))


def build_net(kind: str, in_channels: int, out_channels: int, channels=None, **unet_options) -> nn.Module:
    """``"unet"`` or ``"skip"`` with the paper's widths unless ``channels`` is given; ``unet_options``
    (``down``, ``up``, ``pad``) go to :class:`UNet`."""
    if kind == "unet":
        return UNet(in_channels, out_channels, channels or UNET_CHANNELS, **unet_options)
    if kind == "skip":
        channels = tuple(channels or SKIP_CHANNELS)
        return SkipNet(in_channels, out_channels, channels, tuple(min(4, c) for c in channels))
    raise ValueError(f"net must be 'unet' or 'skip', got {kind!r}")


def smallest_input(kind: str, channels=None) -> int:
    """The smallest height (and width) in px a fit with the net ``kind`` and encoder ``channels`` takes:
    its total down-sampling factor + 1, so the deepest level is at least 2×2 (BatchNorm needs more
    than one value per channel; a 3×3 reflection pad needs 2 px), and at least the losses' 11×11
    SSIM window."""
    if kind == "unet":
        factor = 2 ** (len(tuple(channels or UNET_CHANNELS)) - 1)
    else:
        factor = 2 ** len(tuple(channels or SKIP_CHANNELS))
    return max(factor + 1, 11)


def check_input_size(kind: str, channels, height: int, width: int, name: str = "depth") -> None:
    """``ValueError`` naming ``name`` if a ``height × width`` input is smaller than :func:`smallest_input`."""
    smallest = smallest_input(kind, channels)
    if min(height, width) < smallest:
        raise ValueError(f"{name} is {height}×{width} px (H×W), but the {kind} of this config (encoder widths "
                         f"{tuple(channels) if channels else 'the paper’s'}) needs at least {smallest} px on each "
                         f"side (its deepest level must be 2×2 or more); upsample the inputs or use fewer "
                         f"config.channels")


def count_parameters(net: nn.Module) -> int:
    """Number of trainable parameters."""
    return sum(p.numel() for p in net.parameters() if p.requires_grad)
