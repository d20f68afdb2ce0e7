"""SSIM, masked L1 and the three DDP losses (paper Sec. 3.2, supplement "SSIM Index").

Every loss here is ``λ · L1 + (1 - λ) · (1 - SSIM)`` on some pair of images; they differ in what
is compared and which pixels count:

- ``L_disp``: output vs input disparity, only where the input depth is valid;
- ``L_rgb``: output vs input colour, everywhere;
- ``L_warp``: the reference colour vs each neighbour warped through the output depth, only where
  the warp lands inside the neighbour.

Three more terms are the kit's, not the paper's, all on the disparity in the holes
(:mod:`ddp_lite.method.hole_terms` adds them to the paper's loss): :func:`smoothness_loss`, a curvature
penalty (``FitConfig.smoothness``), and :func:`flatness_loss`, a first-order one
(``FitConfig.flatness``), both weaker across colour edges, on in the ``kit`` recipe at ``ci`` and
``class`` (:data:`ddp_lite.method.recipes.KIT_AT` says why); and :func:`affinity_loss`, tried, off by default.
The ``paper`` recipe has none.

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
from scipy import ndimage

__all__ = ["ssim", "masked_l1", "disparity_loss", "rgb_loss", "warp_loss", "smoothness_weights", "smoothness_loss", "flatness_loss",
           "flatness_region", "ConstantTarget", "EDGE_GUIDES"]

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


EDGE_GUIDES = ("grey", "rgb", "structure")
STRUCTURE_TV_WEIGHT = 0.1  # ROF weight of the "structure" guide, for images in [0, 1]


def smoothness_weights(image, region, edge: float = 10.0, guide: str = "grey") -> torch.Tensor:
    """Per-pixel weights (1, 2, H, W) of :func:`smoothness_loss` and :func:`flatness_loss`:
    ``exp(-edge · g)`` along x (channel 0) and y (channel 1), zero outside ``region`` (1, 1, H, W)
    bool and on the one-pixel border where a second difference does not exist. ``g`` is the
    colour change across the pixel (half its central difference) of ``image`` (B, 3, H, W) in
    [0, 1]: of the grey image (``guide="grey"``), or the largest over the three channels
    (``"rgb"``), which also sees edges between colours of equal brightness, or of the grey image's
    *structure* (``"structure"``: its total-variation (ROF) denoising, weight 0.1, which removes
    texture and keeps strong edges), so that texture on one surface does not switch the terms off.
    Constant during a fit, so it is computed once.

    Example:
        >>> image = torch.zeros(1, 3, 1, 4); image[0, 0, 0, 2:] = 1.0  # black | red: grey steps by 1/3
        >>> region = torch.ones(1, 1, 1, 4, dtype=torch.bool)
        >>> [round(v, 3) for v in smoothness_weights(image, region, 3.0, "grey")[0, 0, 0].tolist()]
        [0.0, 0.607, 0.607, 0.0]
        >>> [round(v, 3) for v in smoothness_weights(image, region, 3.0, "rgb")[0, 0, 0].tolist()]
        [0.0, 0.223, 0.223, 0.0]
    """
    if guide not in EDGE_GUIDES:
        raise ValueError(f"guide must be one of {EDGE_GUIDES}, got {guide!r}")
    source = image.mean(dim=1, keepdim=True) if guide != "rgb" else image  # (B, 1 or 3, H, W)
    if guide == "structure":
        from skimage.restoration import denoise_tv_chambolle
        grey = source.detach().to("cpu", torch.float64).numpy()[:, 0]  # (B, H, W)
        structure = np.stack([denoise_tv_chambolle(g, weight=STRUCTURE_TV_WEIGHT) for g in grey])[:, None]
        source = torch.from_numpy(structure).to(image.device, image.dtype)  # (B, 1, H, W)
    gx = torch.zeros_like(source[:, :1])  # (B, 1, H, W)
    gy = torch.zeros_like(source[:, :1])
    # central differences: the colour change across the pixel whose curvature is penalised
    gx[..., 1:-1] = ((source[..., 2:] - source[..., :-2]).abs() / 2).amax(dim=1, keepdim=True)
    gy[..., 1:-1, :] = ((source[..., 2:, :] - source[..., :-2, :]).abs() / 2).amax(dim=1, keepdim=True)
    weights = torch.cat([torch.exp(-edge * gx), torch.exp(-edge * gy)], dim=1) * region.to(source.dtype)
    weights[:, 0, :, [0, -1]] = 0.0
    weights[:, 1, [0, -1], :] = 0.0
    return weights


def smoothness_loss(disparity: torch.Tensor, weights: torch.Tensor, normaliser: torch.Tensor | None = None) -> torch.Tensor:
    """Edge-aware second-order smoothness of ``disparity`` (B, 1, H, W): the weighted mean of
    |∂²z/∂x²| and |∂²z/∂y²| with ``weights`` (1, 2, H, W) from :func:`smoothness_weights`.
    ``normaliser``: what the weighted sum is divided by (default ``weights.sum()``, which a fit
    computes once and passes in, since the weights are constant).

    Second differences vanish on any plane (disparity is affine in the pixel coordinates on a
    plane), so the term costs nothing there; it only stops the output from bending where no
    data constrains it, and less so across colour edges, where depth edges usually are.
    """
    # second differences exist only inside the one-pixel border, where the weights are 0 anyway:
    # compare the interior slices directly instead of padding to (B, 2, H, W) every iteration
    dxx = disparity[..., 2:] - 2 * disparity[..., 1:-1] + disparity[..., :-2]  # (B, 1, H, W - 2)
    dyy = disparity[..., 2:, :] - 2 * disparity[..., 1:-1, :] + disparity[..., :-2, :]  # (B, 1, H - 2, W)
    weighted = (dxx.abs() * weights[:, :1, :, 1:-1]).sum() + (dyy.abs() * weights[:, 1:, 1:-1, :]).sum()
    total = weights.sum() if normaliser is None else normaliser
    return weighted / total.clamp(min=1e-12) / disparity.shape[0]


def flatness_loss(disparity: torch.Tensor, weights: torch.Tensor, normaliser: torch.Tensor | None = None) -> torch.Tensor:
    """Edge-aware first-order smoothness of ``disparity`` (B, 1, H, W): the weighted mean of
    |∂z/∂x| and |∂z/∂y| (forward differences) with the ``weights`` of :func:`smoothness_weights`.
    ``normaliser``: what the weighted sum is divided by (default ``weights.sum()``); with weights
    cut to a part of the holes (:func:`flatness_region`) pass the sum of the uncut ones, so that a
    pixel there pulls as hard as it would with the term everywhere.

    Where a hole lies between valid pixels a plane through them is among its minima (along a
    line, any monotone profile between two fixed ends has the same variation), but where a hole
    reaches the image border the minimum levels off instead of carrying the last slope outward,
    as the curvature term alone lets it; colorization, a first-order fill, does the same.

    Example:
        >>> ramp = torch.arange(8.0).repeat(8, 1)[None, None] / 8  # (1, 1, 8, 8), slope 1/8 along x
        >>> w = smoothness_weights(torch.zeros(1, 3, 8, 8), torch.ones(1, 1, 8, 8, dtype=torch.bool))
        >>> round(flatness_loss(ramp, w).item(), 4)  # 1/8 × (8·6 x-weights) / (8·6 + 6·8 weights)
        0.0625
    """
    dx = (disparity[..., 1:] - disparity[..., :-1]).abs()  # (B, 1, H, W - 1)
    dy = (disparity[..., 1:, :] - disparity[..., :-1, :]).abs()  # (B, 1, H - 1, W)
    weighted = (dx * weights[:, :1, :, :-1]).sum() + (dy * weights[:, 1:, :-1, :]).sum()
    total = weights.sum() if normaliser is None else normaliser
    return weighted / total.clamp(min=1e-12) / disparity.shape[0]


def flatness_region(holes: np.ndarray, reach: float) -> np.ndarray:
    """Where :func:`flatness_loss` should act, (H, W) bool: every pixel of a hole (4-connected) that
    touches the image border, and in the other, enclosed holes the pixels within ``reach`` px
    (Euclidean) of a pixel outside the holes. ``holes``: (H, W) bool, True where the fit is free.

    At the border nothing on the far side says where the surface goes, and levelling off is the
    safe guess; in a thin hole the term keeps the fill from wandering. But the middle of a large
    enclosed hole has valid depth all around it: there the curvature term alone continues a
    curved surface smoothly, as biharmonic interpolation does, and a first-order term flattens it.

    Example:
        >>> holes = np.zeros((7, 9), bool); holes[2:5, 1:8] = True; holes[0:2, 0] = True
        >>> flatness_region(holes, reach=1.0).astype(int)
        array([[1, 0, 0, 0, 0, 0, 0, 0, 0],
               [1, 0, 0, 0, 0, 0, 0, 0, 0],
               [0, 1, 1, 1, 1, 1, 1, 1, 0],
               [0, 1, 0, 0, 0, 0, 0, 1, 0],
               [0, 1, 1, 1, 1, 1, 1, 1, 0],
               [0, 0, 0, 0, 0, 0, 0, 0, 0],
               [0, 0, 0, 0, 0, 0, 0, 0, 0]])
    """
    holes = np.asarray(holes, bool)
    labels, _ = ndimage.label(holes)  # 4-connected components
    at_border = np.unique(np.concatenate([labels[0], labels[-1], labels[:, 0], labels[:, -1]]))
    touching = np.isin(labels, at_border[at_border > 0])
    return touching | (holes & (ndimage.distance_transform_edt(holes) <= reach))


STEP_RATIO = 1.15  # a depth step: the valid disparities near a pixel differ by more than 15 %


def step_region(holes: np.ndarray, disparity: np.ndarray, reach: float) -> np.ndarray:
    """The hole pixels beside a depth step of the valid input, (H, W) bool: those whose disk of
    radius ``reach`` px holds valid disparities differing by more than :data:`STEP_RATIO` (largest
    over smallest). ``holes`` (H, W) bool, True where the fit is free; ``disparity`` (H, W), any
    positive unit, read where ``holes`` is False.

    Such a hole is typically an occlusion: the band a foreground edge hides in the other view,
    which belongs to the *far* surface. Curvature and flatness there carry the near surface's
    slope into the band; with them off, the net's prior and the colour decide where the step goes.

    Example:
        >>> holes = np.zeros((1, 9), bool); holes[0, 3:6] = True
        >>> disparity = np.array([[2.0, 2, 2, 0, 0, 0, 1, 1, 1]])  # near | hole | far
        >>> step_region(holes, disparity, reach=3.0).astype(int)  # every pixel sees both sides
        array([[0, 0, 0, 1, 1, 1, 0, 0, 0]])
        >>> step_region(holes, disparity, reach=2.0).astype(int)  # only the middle one does
        array([[0, 0, 0, 0, 1, 0, 0, 0, 0]])
        >>> bool(step_region(holes, np.where(disparity > 0, 1.0, 0.0), reach=3.0).any())  # one level: no step
        False
    """
    holes = np.asarray(holes, bool)
    valid = ~holes & np.isfinite(disparity) & (disparity > 0)
    r = int(np.floor(reach))
    yy, xx = np.mgrid[-r:r + 1, -r:r + 1]
    disk = yy ** 2 + xx ** 2 <= reach ** 2
    nearest_high = ndimage.maximum_filter(np.where(valid, disparity, -np.inf), footprint=disk, mode="constant",
                                          cval=-np.inf)
    nearest_low = ndimage.minimum_filter(np.where(valid, disparity, np.inf), footprint=disk, mode="constant",
                                         cval=np.inf)
    with np.errstate(invalid="ignore", divide="ignore"):
        return holes & np.isfinite(nearest_low) & (nearest_high > STEP_RATIO * nearest_low)


def affinity_loss(disparity: torch.Tensor, affinities: torch.Tensor, offsets, region: torch.Tensor,
                  normaliser: torch.Tensor) -> torch.Tensor:
    """Levin et al.'s colorization energy as a hole term: Σ_p∈region |z_p − Σ_q w_pq z_q| / ``normaliser``.

    ``disparity`` (B, 1, H, W); ``affinities`` (1, 8, H, W), the weights w_pq of each pixel's 3×3
    neighbours q at ``offsets`` (eight (dy, dx), ``baselines.colorization_affinities``), summing to 1;
    ``region`` (1, 1, H, W) float, where the term acts (the holes). Zero where every pixel is the
    affinity-weighted mean of its neighbours: a colorization fill is its minimum in the holes.
    Unlike the exp(−edge·|∇I|) weights of :func:`smoothness_weights`, these adapt to the local colour
    variance, so a textured surface stays linked while the boundary between two surfaces does not.

    Example:
        >>> w = torch.full((1, 8, 3, 3), 1 / 8)
        >>> offsets = [(dy, dx) for dy in (-1, 0, 1) for dx in (-1, 0, 1) if (dy, dx) != (0, 0)]
        >>> z = torch.zeros(1, 1, 3, 3); z[..., 1, 1] = 1.0  # a spike in the middle
        >>> region = torch.zeros(1, 1, 3, 3); region[..., 1, 1] = 1.0
        >>> affinity_loss(z, w, offsets, region, region.sum()).item()  # its neighbours' mean is 0
        1.0
    """
    H, W = disparity.shape[-2:]
    padded = F.pad(disparity, (1, 1, 1, 1), mode="replicate")  # (B, 1, H + 2, W + 2); weight 0 outside
    mean = sum(affinities[:, k:k + 1] * padded[..., 1 + dy:1 + dy + H, 1 + dx:1 + dx + W]
               for k, (dy, dx) in enumerate(offsets))  # (B, 1, H, W)
    return ((disparity - mean).abs() * region).sum() / normaliser.clamp(min=1e-12) / disparity.shape[0]
