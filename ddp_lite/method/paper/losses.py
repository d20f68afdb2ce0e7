"""SSIM, masked L1 and the three DDP losses (paper Sec. 3.2, supplement "SSIM Index").

Every loss here is ``λ · L1 + (1 - λ) · (1 - SSIM)`` on some pair of images; they differ in what
is compared and which pixels count:

- ``L_disp``: output vs input disparity, only where the input depth is valid;
- ``L_rgb``: output vs input colour, everywhere;
- ``L_warp``: the reference colour vs each neighbour warped through the output depth, only where
  the warp lands inside the neighbour.

The kit's own terms on the disparity in the holes, not the paper's, live in
:mod:`ddp_lite.method.kit.hole_losses`.

Masking SSIM needs care: an 11×11 window centred on a valid pixel next to a hole would see the
hole's values. So before SSIM both images get the *same* value wherever a pixel does not count
(the target's value for the output, a constant for a target's holes): those pixels then agree
exactly, contribute no error, and pass no gradient. The ground truth inside a hole never
reaches the loss.

A fit compares its output with the same targets every iteration. :class:`ConstantTarget` does
the target's share of the work once (holes set to 0, the mask as float weights and its count,
the target's blurred SSIM moments μ_y and E[y²]); every loss and :func:`ssim` take one where they
take a target, and give the same numbers as with the plain tensor.
"""
from __future__ import annotations

import functools

import numpy as np
import torch
import torch.nn.functional as F

__all__ = ["ssim", "masked_l1", "disparity_loss", "rgb_loss", "warp_loss", "ConstantTarget"]

C1_FACTOR, C2_FACTOR = 0.01, 0.03  # k1, k2 of Wang et al. 2004


@functools.lru_cache(maxsize=16)
def gaussian_kernel_1d(window_size: int, sigma: float, dtype: torch.dtype, device: str) -> torch.Tensor:
    """The normalised 1-D Gaussian (``window_size``,) of ``sigma`` px that SSIM and the image input blur with."""
    offsets = torch.arange(window_size, dtype=torch.float64) - (window_size - 1) / 2
    weights = torch.exp(-offsets ** 2 / (2 * sigma ** 2))
    return (weights / weights.sum()).to(dtype=dtype, device=device)


def blur_valid(x: torch.Tensor, kernel: torch.Tensor) -> torch.Tensor:
    """Separable 'valid' Gaussian filter: (B, C, H, W) → (B, C, H - k + 1, W - k + 1)."""
    C, k = x.shape[1], kernel.numel()
    x = F.conv2d(x, kernel.reshape(1, 1, 1, k).expand(C, 1, 1, k), groups=C)
    return F.conv2d(x, kernel.reshape(1, 1, k, 1).expand(C, 1, k, 1), groups=C)


class ConstantTarget:
    """A loss target (B, C, H, W) that stays the same over many calls, prepared once.

    With ``mask`` (B, 1, H, W) bool, True = the pixel counts: ``image`` is the target with its
    other pixels set to 0 (so the ground truth inside a hole never reaches SSIM's window),
    ``weights`` the mask as floats and ``count`` the L1 normaliser (counted pixels × C, ≥ 1).
    ``moments`` are the target's blurred mean and mean square for :func:`ssim`, so a call blurs
    only the output's channels (x, x², x·y): 3 of 5.

    Example:
        >>> y = torch.rand(1, 1, 16, 16); x = torch.rand(1, 1, 16, 16)
        >>> bool(torch.allclose(ssim(x, ConstantTarget(y)), ssim(x, y)))
        True
    """

    def __init__(self, image: torch.Tensor, mask: torch.Tensor | None = None, window_size: int = 11,
                 sigma: float = 1.5):
        self.mask = mask
        self.image = torch.where(mask, image, torch.zeros_like(image)) if mask is not None else image
        self.weights = mask.to(image.dtype) if mask is not None else None
        self.count = (self.weights.sum() * image.shape[1]).clamp(min=1.0) if mask is not None else None
        self.window = (window_size, float(sigma))
        self.moments = None
        if min(image.shape[-2:]) >= window_size:
            kernel = gaussian_kernel_1d(window_size, float(sigma), image.dtype, str(image.device))
            self.moments = blur_valid(torch.cat([self.image, self.image * self.image], dim=1), kernel).chunk(2, dim=1)


def ssim(x, y, data_range: float = 1.0, window_size: int = 11, sigma: float = 1.5, reduction: str = "mean"):
    """Structural similarity of two images with an 11×11 Gaussian window (σ = 1.5).

    Args:
        x, y: (B, C, H, W) tensors, or NumPy (H, W) / (H, W, C) arrays; H, W ≥ ``window_size``.
            ``y`` may be a :class:`ConstantTarget` (its image; its moments are not blurred again).
        reduction: ``"mean"`` → a scalar (tensor in, tensor out; float for NumPy), the mean over
            the windows that fit inside the image — the number scikit-image's
            ``structural_similarity(gaussian_weights=True, sigma=1.5,
            use_sample_covariance=False)`` gives; ``"none"`` → the SSIM map
            (B, C, H - 10, W - 10), one value per window centre.
    Example:
        >>> img = np.random.default_rng(0).random((32, 32)).astype(np.float32)
        >>> round(ssim(img, img), 6)
        1.0
    """
    as_numpy = not isinstance(x, torch.Tensor)
    target = y if isinstance(y, ConstantTarget) and y.window == (window_size, float(sigma)) else None
    y = y.image if isinstance(y, ConstantTarget) else y
    if as_numpy:
        x_np, y_np = np.asarray(x, dtype=np.float64), np.asarray(y, dtype=np.float64)
        if x_np.shape != y_np.shape or x_np.ndim not in (2, 3):
            raise ValueError(f"x and y must share an (H, W) or (H, W, C) shape, got {x_np.shape} and {y_np.shape}")
        to_tensor = (lambda a: torch.from_numpy(a)[None, None]) if x_np.ndim == 2 else \
                    (lambda a: torch.from_numpy(np.ascontiguousarray(a.transpose(2, 0, 1)))[None])
        x, y = to_tensor(x_np), to_tensor(y_np)
    if x.shape != y.shape or x.ndim != 4:
        raise ValueError(f"x and y must share a (B, C, H, W) shape, got {tuple(x.shape)} and {tuple(y.shape)}")
    if min(x.shape[-2:]) < window_size:
        raise ValueError(f"images must be at least {window_size}×{window_size}, got {tuple(x.shape[-2:])}")
    kernel = gaussian_kernel_1d(window_size, float(sigma), x.dtype, str(x.device))
    c1, c2 = (C1_FACTOR * data_range) ** 2, (C2_FACTOR * data_range) ** 2
    if target is not None and target.moments is not None:  # y's moments are blurred already
        mu_y, yy = target.moments
        mu_x, xx, xy = blur_valid(torch.cat([x, x * x, x * y], dim=1), kernel).chunk(3, dim=1)
    else:  # one batched blur for the five moments instead of five calls
        mu_x, mu_y, xx, yy, xy = blur_valid(torch.cat([x, y, x * x, y * y, x * y], dim=1), kernel).chunk(5, dim=1)
    var_x, var_y, cov = xx - mu_x ** 2, yy - mu_y ** 2, xy - mu_x * mu_y
    ssim_map = ((2 * mu_x * mu_y + c1) * (2 * cov + c2)) / ((mu_x ** 2 + mu_y ** 2 + c1) * (var_x + var_y + c2))
    if reduction == "none":
        return ssim_map
    if reduction != "mean":
        raise ValueError(f"reduction must be 'mean' or 'none', got {reduction!r}")
    value = ssim_map.mean()
    return float(value) if as_numpy else value


def masked_l1(x: torch.Tensor, y: torch.Tensor, mask: torch.Tensor | None = None) -> torch.Tensor:
    """Mean |x - y| over the pixels where ``mask`` (B, 1, H, W) is True; x, y (B, C, H, W)."""
    error = (x - y).abs()
    if mask is None:
        return error.mean()
    weights = mask.to(error.dtype)
    return (error * weights).sum() / (weights.sum() * x.shape[1]).clamp(min=1.0)


def _l1_ssim(x, y: ConstantTarget, mask, l1_weight: float) -> torch.Tensor:
    """``l1_weight · L1 + (1 - l1_weight) · (1 - SSIM)``, with pixels outside ``mask`` (default: the
    target's own) made to agree."""
    mask = y.mask if mask is None else mask
    if mask is not None:
        x = torch.where(mask, x, y.image)
    if mask is not None and mask is y.mask:  # the target's mask: weights and count are ready
        l1 = ((x - y.image).abs() * y.weights).sum() / y.count
    else:
        l1 = masked_l1(x, y.image, mask)
    return l1_weight * l1 + (1.0 - l1_weight) * (1.0 - ssim(x, y))


def _prepared(target, mask) -> ConstantTarget:
    """``target`` as a :class:`ConstantTarget` (with ``mask``); a prepared one must come without a mask."""
    if isinstance(target, ConstantTarget):
        if mask is not None and mask is not target.mask:
            raise ValueError("pass the mask to ConstantTarget(target, mask), not with a prepared target")
        return target
    return ConstantTarget(target, mask)


def disparity_loss(output: torch.Tensor, target, mask: torch.Tensor | None = None, lambda_z: float = 0.8):
    """L_disp: output (B, 1, H, W) vs target disparity, on pixels where ``mask`` (B, 1, H, W) is True.

    The target's non-counting pixels may hold anything finite (NaN is refused: it would poison
    SSIM); they never reach the loss or its gradient. ``target`` may be a
    ``ConstantTarget(target, mask)`` made once per fit (then no ``mask`` here): same value.
    """
    if mask is None and not isinstance(target, ConstantTarget):
        raise ValueError("disparity_loss needs a mask (or a ConstantTarget made with one)")
    return _l1_ssim(output, _prepared(target, mask), None, lambda_z)


def rgb_loss(output: torch.Tensor, target, mask: torch.Tensor | None = None, lambda_i: float = 0.5):
    """L_RGB: output colour (B, 3, H, W) vs the input image (a tensor or a :class:`ConstantTarget`),
    on every pixel (or on ``mask`` (B, 1, H, W)). Arguments in :func:`disparity_loss`'s order."""
    if mask is not None and not isinstance(mask, torch.Tensor):
        raise TypeError(f"rgb_loss: mask must be a bool tensor (B, 1, H, W) or None, got {type(mask).__name__}; "
                        f"pass the weight as lambda_i=")
    return _l1_ssim(output, _prepared(target, mask), None, lambda_i)


def warp_loss(reference: torch.Tensor, warped: list, valid: list, lambda_w: float = 0.5):
    """L_warp: mean over neighbours of ``λw (1 - SSIM) + (1 - λw) L1`` between the reference image
    (B, 3, H, W) and each warped neighbour (B, 3, H, W), on that neighbour's valid pixels (B, 1, H, W).
    ``reference`` may be a :class:`ConstantTarget` without a mask.

    Note the paper weights SSIM by λw here (L1 by λ in the other two losses); with λw = 0.5 the
    two readings agree.
    """
    if len(warped) == 0:
        raise ValueError("warp_loss needs at least one warped neighbour")
    reference = _prepared(reference, None)
    if reference.mask is not None:
        raise ValueError("warp_loss: the reference must not carry a mask (each neighbour has its own)")
    losses = [_l1_ssim(w, reference, v, 1.0 - lambda_w) for w, v in zip(warped, valid)]
    return torch.stack(losses).mean()
