"""The paper's method in one screen: the loss Deep Depth Prior minimises (Sec. 3 of the paper).

    θ* = argmin_θ L_total(f_θ(n)),  Z* = f_θ*(n),  D* = depth of Z*                     (Eq. 1)
    L_total = γ1 L_disp + γ2 L_RGB + (1 - γ1 - γ2) L_warp                                 (Eq. 2)
    L_disp  = λz L1(Z_in, Z_out) + (1 - λz) (1 - SSIM(Z_in, Z_out)), valid pixels only    (Eq. 3)
    L_RGB   = λI L1(I_in, I_out) + (1 - λI) (1 - SSIM(I_in, I_out))                       (Eq. 4)
    L_warp  = 1/N Σ_nbr λw (1 - SSIM(I_ref, W_nbr)) + (1 - λw) L1(I_ref, W_nbr)           (Eq. 5)

Z is normalised disparity (:class:`~ddp_lite.method.disparity.DisparityTransform`: clip the depth to
[d_min, d_max], add c, invert, scale to [0, 1]); n is fixed noise (:func:`~ddp_lite.method.nets.make_input`);
W_nbr is a neighbour's image warped into the reference view through the predicted depth, bilinearly
(:class:`~ddp_lite.method.warp.Warper`); SSIM is 11×11 (:mod:`ddp_lite.method.losses`). γ per variant
(:mod:`ddp_lite.method.variants`): depth-only (1, 0), RGBD (0.98, 0.01), RGBD+warp (0.96, 0.02);
λz 0.8, λI 0.5, λw 0.5. Adam minimises it (:func:`ddp_lite.method.loop.run`), in the paper at lr 5e-5,
×0.01 at iterations 12000 and 15000 of 16000 (6000 for depth only).

The kit's additions sit beside this, each in its own module: terms in the holes
(:mod:`ddp_lite.method.hole_terms`) and other net inputs (:mod:`ddp_lite.method.nets`), both off in
the ``paper`` recipe; the warp term's occlusion test (:mod:`ddp_lite.method.visibility`, off unless
asked for), its confidence mask (:mod:`ddp_lite.method.warp_confidence`, off unless asked for) and its
restriction to the holes (:func:`warp_region`, off unless asked for), its census or gradient cost and
per-pixel texture weights (:mod:`ddp_lite.method.warp_cost`, off unless asked for); auto-stop (:mod:`ddp_lite.method.loop`, a profile's budget), ensembles
(:mod:`ddp_lite.method.ensemble`, off unless asked for), bfloat16 (:func:`ddp_lite.method.device.use_bf16`).
"""
from __future__ import annotations

import numpy as np
import torch
from scipy import ndimage

from .config import FitConfig
from .disparity import DisparityTransform
from .losses import ConstantTarget, disparity_loss, rgb_loss, warp_loss
from .variants import get_variant
from .warp import Warper
from .warp_confidence import warp_confidence
from .warp_cost import WarpCost, epipolar_directions, texture_weights

__all__ = ["PaperLoss", "warp_region"]


def warp_region(fit_mask: torch.Tensor, reach: float) -> torch.Tensor:
    """(1, 1, H, W) bool: the pixels the warp term keeps with ``FitConfig.warp_reach`` (the kit's, not the
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


class PaperLoss:
    """L_total (Eq. 2) of one fit: ``loss(Z_out, I_out)`` → (total, {"disp", "rgb", "warp": term}).

    ``target`` (1, 1, H, W) is Z_in and ``fit_mask`` (1, 1, H, W) bool its pixels that count;
    ``rgb`` (1, 3, H, W) is I_in (None without colour); ``neighbors`` (image (1, 3, H, W), Camera)
    pairs seen from ``camera``. The targets' share of the work is done here, once per fit.
    """

    def __init__(self, variant, config: FitConfig, transform: DisparityTransform, target: torch.Tensor,
                 fit_mask: torch.Tensor, rgb: torch.Tensor | None = None, camera=None, neighbors=(), device="cpu"):
        self.config, self.transform = config, transform
        self.w_disp, self.w_rgb, self.w_warp = get_variant(variant).loss_weights(config.gammas)  # γ1, γ2, 1-γ1-γ2
        self.disp_target = ConstantTarget(target, fit_mask)  # Z_in where the depth is valid (holes → 0)
        self.rgb_target = ConstantTarget(rgb) if rgb is not None else None  # I_in, every pixel
        use_warp = self.w_warp > 0
        self.warpers = [Warper(camera, cam, device=device, occlusion=config.warp_occlusion)  # T_nbr^ref; occlusion: the kit's
                        for _, cam in neighbors] if use_warp else []
        self.neighbor_images = [image for image, _ in neighbors] if use_warp else []  # I_nbr
        # the kit's: per neighbour, the pixels whose photometric match singles out one depth (1, 1, H, W) bool,
        # from the images alone, once per fit (it does not depend on the fit's depth)
        self.confident = [warp_confidence(rgb, image, camera, cam, transform.d_min, transform.d_max, config.lambda_w)
                          for image, cam in neighbors] if use_warp and config.warp_confidence else None
        # the kit's: the warp term only in the holes and a ring around them, off the valid input L_disp pins
        self.region = warp_region(fit_mask, config.warp_reach) if use_warp and config.warp_reach is not None else None
        # both as one mask per neighbour, combined here once, not every iteration; None: the paper's warp term
        self.warp_keep = self.confident
        if self.region is not None:
            self.warp_keep = ([self.region & c for c in self.confident] if self.confident
                              else [self.region] * len(self.warpers))
        # the kit's: another photometric cost, or per-pixel weights from the reference's change along each
        # neighbour's epipolar line (method.warp_cost); None: the paper's intensity cost, unweighted
        self.warp_cost = (WarpCost(self.rgb_target, config.warp_cost, config.lambda_w)
                          if use_warp and (config.warp_cost != "intensity" or config.warp_texture) else None)
        self.warp_weights = ([texture_weights(rgb, epipolar_directions(camera, cam).to(device)) for _, cam in neighbors]
                             if use_warp and config.warp_texture else None)

    def __call__(self, disparity: torch.Tensor, colour: torch.Tensor | None = None):
        """``disparity`` (1, 1, H, W) is Z_out, ``colour`` (1, 3, H, W) I_out (the RGBD variants)."""
        config = self.config
        terms = {"disp": disparity_loss(disparity, self.disp_target, lambda_z=config.lambda_z)}  # Eq. 3
        total = self.w_disp * terms["disp"]  # Eq. 2, γ1 L_disp
        if self.w_rgb > 0:
            terms["rgb"] = rgb_loss(colour, self.rgb_target, lambda_i=config.lambda_i)  # Eq. 4
            total = total + self.w_rgb * terms["rgb"]  # Eq. 2, + γ2 L_RGB
        if self.w_warp > 0:
            depth = self.transform.to_depth(disparity)  # D_out_ref: differentiable, a tensor in and out
            pairs = [warper(image, depth) for warper, image in zip(self.warpers, self.neighbor_images)]  # W_nbr^ref
            valid = [p[1] for p in pairs]
            if self.warp_keep is not None:  # the kit's masks
                valid = [v & keep for v, keep in zip(valid, self.warp_keep)]
            if self.warp_cost is None:
                terms["warp"] = warp_loss(self.rgb_target, [p[0] for p in pairs], valid,
                                          config.lambda_w)  # Eq. 5, mean over the N neighbours
            else:  # the kit's cost or weights, also a mean over the N neighbours
                weights = self.warp_weights or [None] * len(pairs)
                terms["warp"] = torch.stack([self.warp_cost(p[0], v, w) for p, v, w in zip(pairs, valid, weights)]).mean()
            total = total + self.w_warp * terms["warp"]  # Eq. 2, + (1 - γ1 - γ2) L_warp
        return total, terms
