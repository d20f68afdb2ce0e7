"""Other photometric costs for the warp term, and a per-pixel weight on it (the kit's, not the paper's).

The paper's L_warp compares intensities, ``λw (1 − SSIM) + (1 − λw) L1`` on colour (Eq. 5). Where the
two views differ by more than the depth explains (exposure, shading, specular light, a pooled image's
blur) or where the colour is flat, the intensity cost's minimum can sit at a wrong depth: on the real
Motorcycle pair it does for most pixels of the SGBM holes (docs/studies/real_data.md, "Where the warp term can
be trusted"). Three other costs are offered by ``WarpConfig.cost`` (``warp_cost``):

- ``"census"``: a soft census (ternary) transform, as in UnFlow's ternary loss (Meister et al., AAAI
  2018): each pixel is described by the soft signs ``t = d / sqrt(ε + d²)`` of the grey-level
  differences ``d = G(p + o) − G(p)`` to its (2r+1)² − 1 neighbours in a square patch (7×7; ε: about
  10 grey levels, see :data:`CENSUS_EPSILON`), and two pixels
  are compared by a soft Hamming distance, the mean over the patch of ``δ² / (η + δ²)`` with
  ``δ = t_ref − t_warped``. It sees (softly) the order of the grey levels around a pixel, so it is blind
  to a constant brightness offset between the views and nearly so to any monotone change, and where
  the colour is flat the soft signs are near 0 in both views whatever the depth: little pull either
  way. It replaces L1 and SSIM (λw is not used).
- ``"gradient"``: the L1 on the images' forward differences along x and y (per colour channel) in
  place of the L1 on intensities, beside the same SSIM: blind to a constant offset between the views.
- ``"census+intensity"``: half each, ``0.5 (λw (1 − SSIM) + (1 − λw) L1) + 0.5 · 0.59 · census``
  (:data:`CENSUS_SCALE`: the census at the paper's cost's size, so the sum keeps the term's size). The
  census sees the order of the grey levels, blind to offsets and with little pull in flat colour; the
  intensity half keeps the paper's pull where the census is weak.

``WarpConfig.texture`` (``warp_texture``) weights each pixel's cost by how well the neighbour can constrain its depth:
a change of depth moves the pixel's match along its epipolar line, so the cost can tell depths apart
only where the reference image changes along that line. The weight is the grey level's derivative
along the epipolar direction ``s = |∇G · e|`` (:func:`epipolar_directions`), made ``s / (s + median(s))``
(flat colour near 0, any clear edge near 1, so strong edges, where occlusions also lie, do not
dominate), then divided by its image mean, so the term keeps the paper's overall size.

Tried on the real pair and on rendered scenes, none of them kept (docs/studies/real_data.md, "Other photometric
costs for the warp term").

``WarpConfig.combine = "min"`` (``warp_combine``) needs each neighbour's cost per pixel (:meth:`WarpCost.pixel_costs`):
``(1 − λw) · L1 + λw · (1 − SSIM)`` at each pixel, the L1 averaged over the colour channels and the SSIM
that of the 11×11 window centred on the pixel (the images mirrored at the border, so every pixel has
one), or the census distance at the pixel.

Conventions: images (B, C, H, W) in [0, 1]; masks (B, 1, H, W) bool, True = the pixel counts; a pixel
that does not count gets the reference's value in the warped image before any patch is compared (as
:mod:`ddp_lite.method.paper.losses` does for SSIM), so it agrees exactly and passes no gradient.
"""
from __future__ import annotations

import numpy as np
import torch
import torch.nn.functional as F

from ...core.camera import Camera, pixel_grid, relative_pose
from ..paper.losses import ConstantTarget, ssim, warp_loss

__all__ = ["WARP_COSTS", "SSIM_WINDOW", "CENSUS_RADIUS", "CENSUS_SCALE", "grey", "soft_census", "census_distance",
           "forward_differences", "epipolar_directions", "texture_weights", "WarpCost"]

WARP_COSTS = ("intensity", "census", "gradient", "census+intensity")  # "intensity": the paper's
SSIM_WINDOW = 11  # the paper's SSIM window (method.paper.losses); per pixel, the one centred on it
CENSUS_RADIUS = 3  # 7×7 patches, UnFlow's
# UnFlow's soft sign, on grey levels 0-255, is d / sqrt(0.81 + d²): ±0.74 at one grey level, so in a pooled
# photograph's flat colour the signs are noise. Here ε = (10 grey levels)², on [0, 1]: on the real pair's valid
# input (where the input depth is known) the cost's per-pixel minimum then agrees with that depth about as often
# as the intensity cost's does, and more often than with UnFlow's ε (docs/studies/real_data.md, "Other
# photometric costs for the warp term")
CENSUS_EPSILON = (10.0 / 255.0) ** 2
HAMMING_ETA = 0.1  # UnFlow's: one flipped sign costs 4 / 4.1, a sign against 0 1 / 1.1
# the census's mean per pixel at the true depth on the real pair's valid input is 1/0.59 of L1 + SSIM's (0.565-0.616
# over the five cases; benchmarks/study_warp_costs.py --scale): "census+intensity" scales its census half by this
CENSUS_SCALE = 0.59
GREY = (0.299, 0.587, 0.114)  # ITU-R BT.601 luma, as OpenCV's and TensorFlow's rgb → grey


def grey(image: torch.Tensor) -> torch.Tensor:
    """(B, 3, H, W) colour → (B, 1, H, W) luma (BT.601); a one-channel image is returned as it is."""
    if image.shape[1] == 1:
        return image
    weights = torch.tensor(GREY, dtype=image.dtype, device=image.device).reshape(1, 3, 1, 1)
    return (image * weights).sum(dim=1, keepdim=True)


def _offsets(radius: int) -> list:
    """The (dy, dx) of a (2r+1)² patch but its centre, row by row."""
    return [(dy, dx) for dy in range(-radius, radius + 1) for dx in range(-radius, radius + 1) if (dy, dx) != (0, 0)]


def soft_census(image: torch.Tensor, radius: int = CENSUS_RADIUS, epsilon: float = CENSUS_EPSILON) -> torch.Tensor:
    """The soft census of ``image`` (B, 1, H, W): (B, (2r+1)² − 1, H, W), channel k the soft sign
    ``d / sqrt(ε + d²)`` of ``d = I(p + o_k) − I(p)`` for the k-th offset o_k of :func:`_offsets`
    (row by row, the centre left out). Beyond the border the image repeats its edge (d = 0 there)."""
    height, width = image.shape[-2:]
    padded = F.pad(image, (radius, radius, radius, radius), mode="replicate")
    shifted = torch.cat([padded[..., radius + dy:radius + dy + height, radius + dx:radius + dx + width]
                         for dy, dx in _offsets(radius)], dim=1)
    difference = shifted - image
    return difference / torch.sqrt(epsilon + difference * difference)


def census_distance(a: torch.Tensor, b: torch.Tensor, eta: float = HAMMING_ETA) -> torch.Tensor:
    """The soft Hamming distance of two soft censuses (B, K, H, W) → (B, 1, H, W): the mean over the K
    offsets of ``δ² / (η + δ²)``, ``δ = a − b``; 0 for equal censuses, 4 / 4.1 ≈ 0.98 for all signs flipped."""
    delta = a - b
    square = delta * delta
    return (square / (eta + square)).mean(dim=1, keepdim=True)


def forward_differences(image: torch.Tensor) -> torch.Tensor:
    """(B, C, H, W) → (B, 2C, H, W): I(x+1) − I(x) and I(y+1) − I(y), 0 on the last column / row."""
    dx = F.pad(image[..., :, 1:] - image[..., :, :-1], (0, 1, 0, 0))
    dy = F.pad(image[..., 1:, :] - image[..., :-1, :], (0, 0, 0, 1))
    return torch.cat([dx, dy], dim=1)


def epipolar_directions(ref_cam: Camera, nbr_cam: Camera) -> torch.Tensor:
    """(1, 2, H, W) float64: per reference pixel, the unit direction (x, y) in which its match moves
    along its epipolar line as its depth changes: towards or away from the epipole ``e = K C`` (C the
    neighbour's centre in the reference frame), ``e_xy − p·e_z``, the same at every depth
    (as :class:`~ddp_lite.method.kit.visibility.Visibility` marches). A rectified pair: ±x everywhere."""
    centre = torch.tensor(np.linalg.inv(relative_pose(ref_cam, nbr_cam))[:3, 3], dtype=torch.float64)
    epipole = torch.tensor(ref_cam.K, dtype=torch.float64) @ centre
    pixels = pixel_grid(ref_cam.height, ref_cam.width, torch.float64)[:2].reshape(2, ref_cam.height, ref_cam.width)
    velocity = epipole[:2, None, None] - pixels * epipole[2]
    return (velocity / velocity.norm(dim=0, keepdim=True).clamp_min(1e-12))[None]


def texture_weights(reference: torch.Tensor, directions: torch.Tensor) -> torch.Tensor:
    """(1, 1, H, W) per-pixel weights of the warp term from the reference image (1, C, H, W) and the
    epipolar directions (1, 2, H, W) of :func:`epipolar_directions` (module docstring): ``s / (s + m)``
    with s the grey level's central-difference derivative along the direction and m its median over
    the image, then divided by its mean (so the weights average 1). A flat image gets 1 everywhere."""
    g = grey(reference).to(torch.float64)
    padded = F.pad(g, (1, 1, 1, 1), mode="replicate")
    gx = (padded[..., 1:-1, 2:] - padded[..., 1:-1, :-2]) / 2
    gy = (padded[..., 2:, 1:-1] - padded[..., :-2, 1:-1]) / 2
    along = (gx * directions[:, :1] + gy * directions[:, 1:]).abs()
    median = along.median()
    if float(median) <= 0.0:  # half the image flat: its median says nothing; the mean then sets the scale
        median = along.mean()
    if float(median) <= 0.0:  # no change along the line anywhere: no pixel is better than another
        return torch.ones_like(g).to(reference.dtype)
    soft = along / (along + median)
    return (soft / soft.mean()).to(reference.dtype)


class WarpCost:
    """The warp term's cost of one fit against a fixed reference image (1, C, H, W), prepared once:
    ``cost(warped, valid, weights=None)`` → scalar, for one neighbour's warped image (1, C, H, W)
    and its valid pixels (1, 1, H, W) bool; ``weights`` (1, 1, H, W) scale each pixel's share.

    ``kind="intensity"`` without weights is exactly the paper's ``λw (1 − SSIM) + (1 − λw) L1``
    (:func:`~ddp_lite.method.paper.losses.warp_loss`'s per-neighbour term). With weights, L1 (or the gradient
    L1) is a weighted mean over the valid pixels and SSIM a weighted mean over the 11×11 windows, each
    weighted by its centre pixel's weight; census is a weighted mean over the valid pixels.
    ``kind="census+intensity"`` is ``0.5 · intensity + 0.5 · CENSUS_SCALE · census``, each half as above.

    Example:
        >>> ref = torch.rand(1, 3, 16, 16); valid = torch.ones(1, 1, 16, 16, dtype=torch.bool)
        >>> [round(float(WarpCost(ref, kind)(ref.clone(), valid)), 6) for kind in WARP_COSTS]
        [0.0, 0.0, 0.0, 0.0]
    """

    def __init__(self, reference: torch.Tensor, kind: str = "intensity", lambda_w: float = 0.5):
        if kind not in WARP_COSTS:
            raise ValueError(f"warp cost must be one of {WARP_COSTS}, got {kind!r}")
        self.kind, self.lambda_w = kind, float(lambda_w)
        self.target = reference if isinstance(reference, ConstantTarget) else ConstantTarget(reference)
        image = self.target.image
        self.census = soft_census(grey(image)) if kind in ("census", "census+intensity") else None  # the reference's, once
        self.differences = forward_differences(image) if kind == "gradient" else None
        self._mirrored = None  # the reference mirrored by half a window, for per-pixel SSIM (made when first needed)

    def __call__(self, warped: torch.Tensor, valid: torch.Tensor, weights: torch.Tensor | None = None) -> torch.Tensor:
        if self.kind == "census+intensity":  # half the paper's cost, half the census at its size
            return (0.5 * self._cost("intensity", warped, valid, weights)
                    + 0.5 * CENSUS_SCALE * self._cost("census", warped, valid, weights))
        return self._cost(self.kind, warped, valid, weights)

    def _cost(self, kind: str, warped: torch.Tensor, valid: torch.Tensor, weights: torch.Tensor | None) -> torch.Tensor:
        """One of the single costs ("intensity", "census", "gradient") of ``warped`` against the reference."""
        reference = self.target.image
        if kind == "intensity" and weights is None:  # the paper's term, bit for bit
            return warp_loss(self.target, [warped], [valid], self.lambda_w)
        warped = torch.where(valid, warped, reference)  # pixels that do not count agree exactly
        share = valid.to(warped.dtype) if weights is None else valid.to(warped.dtype) * weights
        if kind == "census":
            distance = census_distance(soft_census(grey(warped)), self.census)  # (1, 1, H, W)
            return (distance * share).sum() / share.sum().clamp(min=1e-12)
        if kind == "gradient":
            error = (forward_differences(warped) - self.differences).abs()  # (1, 2C, H, W)
        else:
            error = (warped - reference).abs()
        l1 = (error * share).sum() / (share.sum() * error.shape[1]).clamp(min=1e-12)
        if weights is None:
            structure = ssim(warped, self.target)
        else:  # each 11×11 window weighted by its centre pixel's weight
            ssim_map = ssim(warped, self.target, reduction="none")  # (1, C, H - 10, W - 10)
            half = (reference.shape[-1] - ssim_map.shape[-1]) // 2
            centre = weights[..., half:half + ssim_map.shape[-2], half:half + ssim_map.shape[-1]]
            structure = (ssim_map * centre).sum() / (centre.sum() * ssim_map.shape[1]).clamp(min=1e-12)
        return (1.0 - self.lambda_w) * l1 + self.lambda_w * (1.0 - structure)

    def pixel_costs(self, warped: torch.Tensor, valid: torch.Tensor) -> torch.Tensor:
        """(1, 1, H, W): the cost of ``warped`` (1, C, H, W) against the reference at each pixel (module
        docstring), where ``valid`` (1, 1, H, W) bool; elsewhere the warped image takes the reference's
        values before any window is compared, so an invalid pixel costs 0 and its neighbours' windows
        see agreement there (as in the paper's term). The cost at a pixel that does not count is
        meaningless: mask it.

        Example:
            >>> ref = torch.rand(1, 3, 16, 16); valid = torch.ones(1, 1, 16, 16, dtype=torch.bool)
            >>> float(WarpCost(ref).pixel_costs(ref.clone(), valid).abs().max())
            0.0
        """
        reference = self.target.image
        warped = torch.where(valid, warped, reference)
        if self.kind == "census":
            return census_distance(soft_census(grey(warped)), self.census)
        if self.kind == "census+intensity":
            return (0.5 * self._intensity_pixel_costs(warped, warped - reference)
                    + 0.5 * CENSUS_SCALE * census_distance(soft_census(grey(warped)), self.census))
        error = forward_differences(warped) - self.differences if self.kind == "gradient" else warped - reference
        return self._intensity_pixel_costs(warped, error)

    def _intensity_pixel_costs(self, warped: torch.Tensor, error: torch.Tensor) -> torch.Tensor:
        """``(1 − λw) · mean_channels |error| + λw · (1 − SSIM of the window centred on each pixel)``."""
        half = SSIM_WINDOW // 2
        if self._mirrored is None:  # the reference's moments over the mirrored image, once
            self._mirrored = ConstantTarget(F.pad(self.target.image, (half,) * 4, mode="reflect"), window_size=SSIM_WINDOW)
        structure = ssim(F.pad(warped, (half,) * 4, mode="reflect"), self._mirrored, window_size=SSIM_WINDOW,
                         reduction="none")  # (1, C, H, W)
        return ((1.0 - self.lambda_w) * error.abs().mean(dim=1, keepdim=True)
                + self.lambda_w * (1.0 - structure.mean(dim=1, keepdim=True)))
