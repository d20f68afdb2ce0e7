"""Where the warp term can be trusted: a per-pixel confidence of the neighbour's photometric evidence.

Not in the paper. L_warp pulls each reference pixel's depth towards the depth at which the warped
neighbour matches the reference colour best. Where that match is ambiguous (flat colour, repeated
texture) or wrong (the neighbour does not see the pixel, a window across a depth edge), the pull
goes to a wrong depth. On the real Motorcycle pair at 125×185 the minimum of the term's own cost
lies within 2 px of the truth for 89–94 % of the pixels of random blob holes, but for only 39 % of
the pixels where SGBM failed (docs/studies/real_data.md, "Where the warp term can be trusted").

The test asks the images alone, once per fit, before the loop (it does not depend on the fit's
depth): a plane sweep of the term's own per-pixel cost (:func:`photometric_cost`, through the same
:class:`~ddp_lite.method.paper.warp.Warper`) over fronto-parallel planes uniform in inverse depth over the
fit's range, then three classical stereo checks on the cost curve:

- **uniqueness** (SGM's uniqueness ratio): ``1 - c_best / c_second ≥ UNIQUENESS``, with c_second
  the lowest cost more than ``EXCLUSION_PX`` of disparity away from the best plane;
- **left-right consistency**: the neighbour's own best plane (a sweep from its side) sends the
  reference's match back within ``LR_TOLERANCE_PX`` of where it started (fails in occlusions);
- **a confident neighbourhood**: both hold on the whole (2r+1)×(2r+1) square around the pixel,
  r = ``ERODE_PX`` (the SSIM window and the net spread one wrong pull to the pixels around it).

Conventions: images (1, 3, H, W) tensors in [0, 1]; cameras in the OpenCV convention; depth along
the optical axis in metres; "px of disparity" is the shift in the neighbour's image.
"""
from __future__ import annotations

import math

import numpy as np
import torch
import torch.nn.functional as F

from ...core.camera import Camera
from ..paper.losses import ssim
from ..paper.warp import Warper

__all__ = ["photometric_cost", "structure_per_pixel", "sweep_planes", "cost_volume", "warp_confidence",
           "UNIQUENESS", "EXCLUSION_PX", "LR_TOLERANCE_PX", "ERODE_PX", "STEP_PX"]

UNIQUENESS = 0.3  # 1 - c_best / c_second at least this (SGBM's uniquenessRatio in percent would be 30)
EXCLUSION_PX = 1.0  # the second minimum is sought more than this many px of disparity from the best
LR_TOLERANCE_PX = 1.0  # the round trip reference → neighbour → reference lands within this many px
ERODE_PX = 2  # a pixel is confident only if its (2r+1)² neighbourhood is
STEP_PX = 0.25  # the sweep's plane spacing, px of disparity at the pixel that moves most
MAX_PLANES = 256
CHUNK = 16  # planes warped at once: bounds the memory of the sweep to 16 warped images


def photometric_cost(reference: torch.Tensor, warped: torch.Tensor, lambda_w: float = 0.5) -> torch.Tensor:
    """The warp term's cost per pixel: ``λw (1 − SSIM) + (1 − λw) |I_ref − W|``, channel-averaged.

    ``reference`` (1, C, H, W), ``warped`` (D, C, H, W) → (D, 1, H, W). SSIM is the loss's 11×11 map
    (one value per window centre), padded to H×W by repeating the border's windows; H, W ≥ 11.
    """
    l1 = (warped - reference).abs().mean(dim=1, keepdim=True)
    return lambda_w * (1.0 - structure_per_pixel(reference, warped)) + (1.0 - lambda_w) * l1


def structure_per_pixel(reference: torch.Tensor, warped: torch.Tensor) -> torch.Tensor:
    """SSIM per pixel, channel-averaged: ``reference`` (1, C, H, W), ``warped`` (D, C, H, W) → (D, 1, H, W),
    the loss's 11×11 map (one value per window centre) padded to H×W by repeating the border's windows."""
    structure = ssim(warped, reference.expand_as(warped), reduction="none").mean(dim=1, keepdim=True)
    half = (reference.shape[-1] - structure.shape[-1]) // 2
    return F.pad(structure, (half, half, half, half), mode="replicate")


def _parallax_px(ref_cam: Camera, nbr_cam: Camera, near: float, far: float) -> float:
    """The largest shift (px) in the neighbour of a reference pixel moved from depth ``far`` to ``near``
    (metres), over a 5×5 grid of pixels: the disparity range the sweep must cover."""
    warper = Warper(ref_cam, nbr_cam, dtype=torch.float64)
    rows = np.linspace(0, ref_cam.height - 1, 5).round().astype(int)
    columns = np.linspace(0, ref_cam.width - 1, 5).round().astype(int)
    rays = warper.rays[0][:, rows][:, :, columns]  # (3, 5, 5)
    ends = [depth * rays + warper.offset[0] for depth in (near, far)]
    uv = [q[:2] / q[2:].clamp(min=1e-9) for q in ends]
    return float((uv[0] - uv[1]).norm(dim=0).max())


def sweep_planes(ref_cam: Camera, nbr_cam: Camera, d_min: float, d_max: float, step_px: float = STEP_PX) -> np.ndarray:
    """(D,) plane depths in metres, near → far, uniform in inverse depth over [d_min, d_max], spaced
    ``step_px`` of disparity at the pixel that moves most (8 ≤ D ≤ ``MAX_PLANES``)."""
    return _planes(_parallax_px(ref_cam, nbr_cam, d_min, d_max), d_min, d_max, step_px)


def _planes(parallax: float, d_min: float, d_max: float, step_px: float = STEP_PX) -> np.ndarray:
    """:func:`sweep_planes` for a sweep whose nearest and farthest planes lie ``parallax`` px apart."""
    count = int(np.clip(math.ceil(parallax / step_px - 1e-6) + 1, 8, MAX_PLANES))  # - 1e-6: round-off of an exact fit
    return 1.0 / np.linspace(1.0 / d_min, 1.0 / d_max, count)


def _cost_slices(reference, neighbour, warper, planes, lambda_w):
    """The cost volume :func:`cost_volume` returns, ``CHUNK`` planes at a time: (d, H, W) each."""
    H, W = reference.shape[-2:]
    for start in range(0, len(planes), CHUNK):
        depths = torch.tensor(planes[start:start + CHUNK], dtype=reference.dtype, device=reference.device)
        depths = depths.reshape(-1, 1, 1, 1).expand(-1, 1, H, W)
        warped, valid = warper(neighbour.expand(len(depths), -1, -1, -1), depths)
        cost = photometric_cost(reference, warped, lambda_w)
        yield torch.where(valid, cost, torch.full_like(cost, math.inf))[:, 0]


@torch.no_grad()
def cost_volume(reference: torch.Tensor, neighbour: torch.Tensor, warper: Warper, planes: np.ndarray,
                lambda_w: float = 0.5) -> torch.Tensor:
    """:func:`photometric_cost` of ``reference`` (1, C, H, W) against ``neighbour`` (1, C, H', W') warped
    by ``warper`` (``Warper(ref_cam, nbr_cam)``, in the images' dtype and on their device) through each
    fronto-parallel plane of ``planes`` (D,) metres → (D, H, W); +inf where the plane sends the pixel
    outside the neighbour or behind it. Memory: D·H·W floats plus ``CHUNK`` warped images (the one volume
    :func:`warp_confidence` keeps: 82 planes at 125×185 is 7.6 MB)."""
    return torch.cat(list(_cost_slices(reference, neighbour, warper, planes, lambda_w)))


def _best_plane(reference, neighbour, warper, planes, lambda_w) -> torch.Tensor:
    """(H, W) long: the plane of least cost, without keeping the volume (the left-right check needs no more)."""
    best_cost = best = None
    start = 0
    for chunk in _cost_slices(reference, neighbour, warper, planes, lambda_w):
        value, index = chunk.min(dim=0)
        if best is None:
            best_cost, best = value, index
        else:
            better = value < best_cost  # strict: ties keep the nearer plane, as argmin over the volume does
            best_cost, best = torch.where(better, value, best_cost), torch.where(better, index + start, best)
        start += len(chunk)
    return best


def _pixel_in_other(warper: Warper, depth: torch.Tensor) -> torch.Tensor:
    """(1, 2, H, W): where each pixel lands in the other camera at ``depth`` (1, 1, H, W) metres."""
    q = depth * warper.rays + warper.offset
    return q[:, :2] / q[:, 2:3].clamp(min=warper.eps)


@torch.no_grad()
def warp_confidence(reference: torch.Tensor, neighbour: torch.Tensor, ref_cam: Camera, nbr_cam: Camera,
                    d_min: float, d_max: float, lambda_w: float = 0.5, uniqueness: float = UNIQUENESS,
                    lr_tolerance_px: float = LR_TOLERANCE_PX, erode_px: int = ERODE_PX) -> torch.Tensor:
    """(1, 1, H, W) bool: True where the neighbour's photometric evidence singles out one depth and the
    neighbour agrees (module docstring), from the images alone.

    Args:
        reference: (1, C, H, W) the reference image in [0, 1].
        neighbour: (1, C, H', W') the neighbour's image, seen by ``nbr_cam``.
        ref_cam, nbr_cam: the two cameras (OpenCV convention, metres).
        d_min, d_max: the depth range of the sweep (metres, 0 < d_min < d_max): the fit's.
        lambda_w: the SSIM share of the cost, the warp term's.
        uniqueness: the least ``1 - c_best / c_second`` (0: any strict minimum).
        lr_tolerance_px: how far (px) the round trip may land from where it started (inf: no check).
        erode_px: r of the neighbourhood that must be confident too (0: the pixel alone).

    Example:
        >>> cam = Camera.from_fov(48, 32, 60.0)
        >>> moved = np.eye(4); moved[0, 3] = -0.1  # the neighbour 0.1 m to the right
        >>> nbr = Camera(cam.K, moved, 48, 32)
        >>> image = torch.rand(1, 3, 32, 48)
        >>> warp_confidence(image, image, cam, nbr, 1.0, 4.0).shape
        torch.Size([1, 1, 32, 48])
    """
    if not 0.0 < d_min < d_max:
        raise ValueError(f"need 0 < d_min < d_max, got d_min={d_min}, d_max={d_max}")
    # the two warps, built once: the sweep from each side and the round trip of the left-right check
    forward = Warper(ref_cam, nbr_cam, dtype=reference.dtype, device=reference.device)  # reference → neighbour
    backward = Warper(nbr_cam, ref_cam, dtype=reference.dtype, device=reference.device)  # neighbour → reference
    parallax = _parallax_px(ref_cam, nbr_cam, d_min, d_max)
    planes = _planes(parallax, d_min, d_max)  # as sweep_planes
    step = max(parallax / (len(planes) - 1), 1e-9)  # px per plane
    cost = cost_volume(reference, neighbour, forward, planes, lambda_w)  # (D, H, W)
    best_cost, best = cost.min(dim=0)  # (H, W)
    index = torch.arange(len(planes), device=cost.device).reshape(-1, 1, 1)
    away = (index - best[None]).abs() > EXCLUSION_PX / step
    second = torch.where(away, cost, torch.full_like(cost, math.inf)).min(dim=0).values
    unique = torch.isfinite(best_cost) & (best_cost < (1.0 - uniqueness) * second)  # inf second: unique

    # left-right: the neighbour's own winner, from its side, must send the match back
    back_best = _best_plane(neighbour, reference, backward, planes, lambda_w)  # (H', W')
    depths = torch.tensor(planes, dtype=reference.dtype, device=reference.device)
    there = _pixel_in_other(forward, depths[best][None, None])  # (1, 2, H, W) in the neighbour
    back = _pixel_in_other(backward, depths[back_best][None, None])  # (1, 2, H', W') in the reference
    grid = there * forward.to_grid - 1.0
    returned = F.grid_sample(back, grid.permute(0, 2, 3, 1), mode="nearest", padding_mode="border",
                             align_corners=True)  # (1, 2, H, W)
    H, W = reference.shape[-2:]
    v, u = torch.meshgrid(torch.arange(H, dtype=reference.dtype, device=reference.device),
                          torch.arange(W, dtype=reference.dtype, device=reference.device), indexing="ij")
    consistent = (returned - torch.stack([u, v])[None]).norm(dim=1)[0] <= lr_tolerance_px

    confident = (unique & consistent)[None, None].to(reference.dtype)  # (1, 1, H, W)
    if erode_px > 0:  # min filter: every pixel of the square must be confident (the border counts as confident)
        size = 2 * erode_px + 1
        confident = -F.max_pool2d(F.pad(-confident, (erode_px,) * 4, value=-1.0), size, stride=1)
    return confident > 0.5
