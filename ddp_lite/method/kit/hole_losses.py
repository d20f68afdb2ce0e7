"""The kit's terms in the holes: not in the paper, added to its loss by the ``kit`` recipe
(:class:`~ddp_lite.method.kit.hole_terms.HoleTerms` adds them to one fit).

    L = L_total (paper, :mod:`ddp_lite.method.paper.total_loss`) + s·L_curv + f·L_flat + a·L_aff

on the disparity Z in the *free* pixels (holes and held-out pixels), each relaxed at colour edges:

- L_curv = Σ w·(|∂²Z/∂x²| + |∂²Z/∂y²|) / Σ w, curvature (``HoleConfig.smoothness`` = s): zero on any
  plane, it keeps a hole far from valid pixels from bending where nothing constrains it;
- L_flat = Σ w'·(|∂Z/∂x| + |∂Z/∂y|) / Σ w, first order (``FitConfig.flatness`` = f): a hole that
  reaches the border levels off instead of carrying the last slope outward; ``flatness_reach``
  limits it, in enclosed holes, to a rim of that many px (w' = w there, 0 elsewhere);
- both off (w = 0) in the holes within ``step_reach`` px of a depth step of the valid input, where a
  hole is likely an occlusion band that belongs to the far side (:func:`step_region`);
- w = exp(-edge·|∇I|) of the grey image, or the largest over R, G, B (``smoothness_edge``,
  ``edge_guide``; :func:`smoothness_weights`);
- L_aff = Σ |Z_p - Σ_q w_pq Z_q| / #free, Levin et al.'s colorization energy
  (``HoleConfig.affinity`` = a; :func:`affinity_loss`).

On in the ``kit`` recipe at ``ci`` and ``class`` (:data:`ddp_lite.method.kit.recipes.KIT_AT` says why), but
the affinity term, tried and off by default; the ``paper`` recipe has none. Why these weights and what
they bought on the quality suite: ``docs/studies/tuning_history.md``.
"""
from __future__ import annotations

import numpy as np
import torch
import torch.nn.functional as F
from scipy import ndimage

__all__ = ["EDGE_GUIDES", "smoothness_weights", "smoothness_loss", "flatness_loss", "flatness_region", "step_region",
           "affinity_loss"]


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
    neighbours q at ``offsets`` (eight (dy, dx), ``guided_fills.colorization_affinities``), summing to 1;
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
