"""The kit's warp term of one fit, handed to the paper's loss as its ``warp_term`` (and its occlusion
tests as its ``visibility``): the masks and costs are built here once per fit, from the settings
(:class:`WarpConfig`, named below as FitConfig takes them: ``warp_cost`` is ``config.warp.cost``) and the
images, and applied each iteration. Each is off unless the config asks for it; with all off
:func:`kit_warp_term` is None and the paper's Eq. 5 runs unchanged.

- ``warp_confidence``: per neighbour, the pixels whose photometric match singles out one depth
  (:mod:`ddp_lite.method.kit.warp_confidence`), from the images alone;
- ``warp_reach``: only the holes and a ring around them, off the valid input L_disp pins (:func:`warp_region`);
- ``warp_cost`` / ``warp_texture``: another photometric cost, or per-pixel weights from the reference's
  change along each neighbour's epipolar line (:mod:`ddp_lite.method.kit.warp_cost`);
- ``warp_occlusion``: a pixel the reference surface hides from the neighbour does not count
  (:mod:`ddp_lite.method.kit.visibility`);
- ``warp_combine="min"``: at each pixel only the neighbour that agrees best counts, not the mean over the
  N (:func:`minimum_over_neighbours`).

Why the minimum: a pixel of the reference that one neighbour cannot see (occluded there, or out of its
frame) warps to the wrong surface in that neighbour, and the mean then pulls the depth towards whatever
makes the wrong surface match; with the rail's neighbours on either side, a pixel hidden on one side is
usually seen on the other, and its cost there is low at the true depth. Monodepth2's per-pixel minimum
reprojection (Godard et al., ICCV 2019) does the same for self-supervised depth.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import torch
from scipy import ndimage

from ...core.checks import check_bool, check_choice, check_real
from ...core.settings import Settings
from ..paper.disparity import DisparityTransform
from ..paper.losses import warp_loss
from .visibility import Visibility
from .warp_confidence import warp_confidence
from .warp_cost import WARP_COSTS, WarpCost, epipolar_directions, texture_weights

WARP_COMBINATIONS = ("mean", "min")  # over the N neighbours: "mean" the paper's (Eq. 5), "min" per pixel

__all__ = ["WARP_COMBINATIONS", "WarpConfig", "WarpTerm", "minimum_over_neighbours", "kit_warp_term", "occlusion_tests", "kit_warp_arguments", "warp_region"]


@dataclass(frozen=True)
class WarpConfig(Settings):
    """The kit's changes to the warp term L_warp (6 fields; the defaults are the paper's Eq. 5). FitConfig takes
    each by its name in ``flat_names`` (``FitConfig(warp_cost="census")`` sets ``config.warp.cost``)."""

    section = "warp"
    flat_names = {"occlusion": "warp_occlusion", "confidence": "warp_confidence", "reach": "warp_reach",
                  "cost": "warp_cost", "texture": "warp_texture", "combine": "warp_combine"}

    occlusion: bool = False  # skip pixels a nearer point hides from the neighbour (visibility.Visibility)
    confidence: bool = False  # only where the images single out one depth (warp_confidence)
    reach: float | None = None  # only on the unfitted pixels (holes, held-out) and within this many px of
    # them, off the valid input L_disp pins (warp_region; None: every pixel, the paper)
    cost: str = "intensity"  # what L_warp compares: "intensity" (L1 + SSIM on colour, the paper), "census" (a
    # soft census, no L1/SSIM), "gradient" (L1 on the images' differences + SSIM) or "census+intensity" (half each,
    # the census at L1 + SSIM's size) (warp_cost)
    texture: bool = False  # weighted per pixel by the reference's change along the epipolar line
    # (warp_cost.texture_weights: flat colour little)
    combine: str = "mean"  # over the N neighbours: "mean" (the paper's Eq. 5) or "min": per pixel the neighbour
    # that agrees best (minimum_over_neighbours)

    def validate(self) -> None:
        check_choice(self.cost, "config.warp_cost", WARP_COSTS)
        check_choice(self.combine, "config.warp_combine", WARP_COMBINATIONS)
        for name in ("occlusion", "confidence", "texture"):
            check_bool(getattr(self, name), f"config.{self.flat_name(name)}")
        if self.combine == "min" and self.texture:
            raise ValueError("config.warp_texture weights each neighbour's cost over the image; with "
                             "config.warp_combine='min' use one or the other")
        if self.reach is not None:
            check_real(self.reach, "config.warp_reach", 0.0)

    def describe(self) -> str:
        """These changes' part of a recipe's one-line description (``kit.recipes.describe_method``); "" for
        the paper's warp term."""
        costs = {"census": ", the warp term on a soft census of 7×7 patches (not L1 + SSIM on intensities)",
                 "gradient": ", the warp term's L1 on the images' differences (not on intensities)",
                 "census+intensity": ", the warp term half L1 + SSIM on intensities, half a soft census of 7×7 "
                                     "patches at its size"}
        return ((", the warp term only where the neighbour can see" if self.occlusion else "")
                + (", the warp term only where the images single out one depth" if self.confidence else "")
                + (f", the warp term only in the holes and within {self.reach:g} px of them"
                   if self.reach is not None else "")
                + costs.get(self.cost, "")
                + (", the warp term weighted by the image's change along each pixel's epipolar line"
                   if self.texture else "")
                + (", the warp term per pixel from the neighbour that agrees best (not their mean)"
                   if self.combine == "min" else ""))

    def equation(self) -> list[str]:
        """These changes as the marks on L_warp in the equation a config optimises (``method.equation``);
        [] for the paper's warp term."""
        return [name for name, on in (("visible", self.occlusion),  # kit.visibility
                                      ("confident", self.confidence),  # kit.warp_confidence
                                      ("holes", self.reach is not None),  # warp_region
                                      (self.cost, self.cost != "intensity"),  # kit.warp_cost
                                      ("textured", self.texture),
                                      ("min over views", self.combine == "min"))
                if on]


def warp_region(fit_mask: torch.Tensor, reach: float) -> torch.Tensor:
    """(1, 1, H, W) bool: the pixels the warp term keeps with ``WarpConfig.reach`` (the kit's, not the
    paper's): those ``fit_mask`` (1, 1, H, W) bool leaves unfitted (holes, held-out pixels) and every pixel
    within ``reach`` px of one (Euclidean distance between pixel centres, so ``reach`` 0 is the holes alone,
    1 adds their 4-neighbours).

    Where the input depth is valid L_disp pins it, and on real data that depth came from the same kind
    of photometric matching the warp term redoes; outside this region the term passes no gradient at all.

    Example:
        >>> mask = torch.ones(1, 1, 1, 7, dtype=torch.bool); mask[..., 3] = False
        >>> warp_region(mask, 1.0)[0, 0, 0].tolist()
        [False, False, True, True, True, False, False]
    """
    free = ~fit_mask[0, 0].cpu().numpy()
    if not free.any():
        return torch.zeros_like(fit_mask)
    near = ndimage.distance_transform_edt(~free) <= reach  # distance to the nearest unfitted pixel, 0 on them
    return torch.from_numpy(np.asarray(near))[None, None].to(fit_mask.device)


def minimum_over_neighbours(costs: list, valid: list) -> torch.Tensor:
    """Scalar: the mean over the pixels some neighbour sees of the smallest cost among the neighbours that
    see it; ``costs`` N maps (1, 1, H, W) of one neighbour's cost per pixel, ``valid`` N masks (1, 1, H, W)
    bool. The gradient reaches, at each pixel, the neighbour with the smallest cost only. No pixel seen:
    0 (with the graph kept, so a fit's backward pass still runs).

    Example:
        >>> costs = [torch.tensor([[[[0.2, 0.9, 0.5]]]]), torch.tensor([[[[0.4, 0.1, 0.7]]]])]
        >>> valid = [torch.tensor([[[[True, True, False]]]]), torch.tensor([[[[True, True, False]]]])]
        >>> round(float(minimum_over_neighbours(costs, valid)), 6)  # (0.2 + 0.1) / 2: the third pixel is seen by none
        0.15
    """
    stacked = torch.cat(costs, dim=1)  # (1, N, H, W)
    seen = torch.cat(valid, dim=1)  # (1, N, H, W) bool
    smallest = torch.where(seen, stacked, torch.full_like(stacked, float("inf"))).amin(dim=1, keepdim=True)
    counted = seen.any(dim=1, keepdim=True)  # (1, 1, H, W)
    total = torch.where(counted, smallest, torch.zeros_like(smallest)).sum()
    return total / counted.sum().clamp(min=1).to(total.dtype)


@dataclass(eq=False)
class WarpTerm:
    """The kit's warp term: ``term(reference, warped, valid)`` → scalar, over the N neighbours (``combine``
    "mean": the mean of each one's cost, "min": per pixel the smallest, :func:`minimum_over_neighbours`)
    of the cost of each warped image (1, 3, H, W) where its ``valid`` (1, 1, H, W) bool and its ``keep``
    mask (None: every valid pixel) agree; ``kind`` None is the paper's intensity cost, else a
    :class:`~ddp_lite.method.kit.warp_cost.WarpCost` of ``kind`` with per-neighbour ``weights``.
    """

    lambda_w: float
    keep: list | None = None
    kind: str | None = None
    weights: list | None = None
    combine: str = "mean"
    # the WarpCost against the paper's reference, made at the first call
    cost: WarpCost | None = field(default=None, init=False, repr=False)

    def __call__(self, reference, warped: list, valid: list) -> torch.Tensor:
        if self.keep is not None:
            valid = [v & keep for v, keep in zip(valid, self.keep)]
        if self.combine == "min":
            if self.cost is None:
                self.cost = WarpCost(reference, self.kind or "intensity", self.lambda_w)
            return minimum_over_neighbours([self.cost.pixel_costs(w, v) for w, v in zip(warped, valid)], valid)
        if self.kind is None:
            return warp_loss(reference, warped, valid, self.lambda_w)  # Eq. 5, mean over the N neighbours
        if self.cost is None:  # the reference is the paper's I_in, prepared once (its SSIM moments, census)
            self.cost = WarpCost(reference, self.kind, self.lambda_w)
        weights = self.weights or [None] * len(warped)
        return torch.stack([self.cost(w, v, t) for w, v, t in zip(warped, valid, weights)]).mean()


def kit_warp_term(config: WarpConfig, lambda_w: float, transform: DisparityTransform, fit_mask: torch.Tensor,
                  rgb: torch.Tensor | None, camera, neighbors, device) -> WarpTerm | None:
    """The warp term ``config`` asks for, with the paper's SSIM share ``lambda_w``, for the paper's loss
    (the other arguments as :class:`~ddp_lite.method.paper.total_loss.PaperLoss`'s; no ``neighbors``: no
    warp term); None where it asks for none of the kit's (the paper's Eq. 5)."""
    if not neighbors:
        return None
    # per neighbour, the pixels whose photometric match singles out one depth (1, 1, H, W) bool,
    # from the images alone, once per fit (it does not depend on the fit's depth)
    keep = ([warp_confidence(rgb, image, camera, cam, transform.d_min, transform.d_max, lambda_w)
             for image, cam in neighbors] if config.confidence else None)
    if config.reach is not None:  # the warp term only in the holes and a ring around them
        region = warp_region(fit_mask, config.reach)
        keep = [region & c for c in keep] if keep else [region] * len(neighbors)
    kind = config.cost if config.cost != "intensity" or config.texture else None
    weights = ([texture_weights(rgb, epipolar_directions(camera, cam).to(device)) for _, cam in neighbors]
               if config.texture else None)
    combine = config.combine
    if keep is None and kind is None and combine == "mean":
        return None
    return WarpTerm(lambda_w, keep, kind, weights, combine)


def occlusion_tests(config: WarpConfig, camera, neighbors, device) -> list | None:
    """One occlusion test per neighbour for the paper's warpers (``config.occlusion``); None: none."""
    if not config.occlusion or not neighbors:
        return None
    return [Visibility(camera, cam, torch.float32, device) for _, cam in neighbors]


def kit_warp_arguments(config: WarpConfig, lambda_w: float, transform: DisparityTransform, fit_mask: torch.Tensor,
                       rgb: torch.Tensor | None, camera, neighbors, device) -> dict:
    """The kit's share of the paper's warp term as :class:`~ddp_lite.method.paper.total_loss.PaperLoss`'s
    keyword arguments: ``warp_term`` (:func:`kit_warp_term`) and ``visibility`` (:func:`occlusion_tests`),
    each None where ``config`` asks for none (the paper's)."""
    return {"warp_term": kit_warp_term(config, lambda_w, transform, fit_mask, rgb, camera, neighbors, device),
            "visibility": occlusion_tests(config, camera, neighbors, device)}
