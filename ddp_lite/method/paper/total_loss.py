"""The paper's method in one screen: the loss Deep Depth Prior minimises (Sec. 3 of the paper).

    θ* = argmin_θ L_total(f_θ(n)),  Z* = f_θ*(n),  D* = depth of Z*                     (Eq. 1)
    L_total = γ1 L_disp + γ2 L_RGB + (1 - γ1 - γ2) L_warp                                 (Eq. 2)
    L_disp  = λz L1(Z_in, Z_out) + (1 - λz) (1 - SSIM(Z_in, Z_out)), valid pixels only    (Eq. 3)
    L_RGB   = λI L1(I_in, I_out) + (1 - λI) (1 - SSIM(I_in, I_out))                       (Eq. 4)
    L_warp  = 1/N Σ_nbr λw (1 - SSIM(I_ref, W_nbr)) + (1 - λw) L1(I_ref, W_nbr)           (Eq. 5)

Z is normalised disparity (:class:`~ddp_lite.method.paper.disparity.DisparityTransform`: clip the depth to
[d_min, d_max], add c, invert, scale to [0, 1]); n is fixed noise (:func:`~ddp_lite.method.paper.nets.make_input`);
W_nbr is a neighbour's image warped into the reference view through the predicted depth, bilinearly
(:class:`~ddp_lite.method.paper.warp.Warper`); SSIM is 11×11 (:mod:`ddp_lite.method.paper.losses`). γ per variant
(:mod:`ddp_lite.method.paper.variants`): depth-only (1, 0), RGBD (0.98, 0.01), RGBD+warp (0.96, 0.02);
λz 0.8, λI 0.5, λw 0.5. Adam minimises it (:func:`ddp_lite.method.loop.run`), in the paper at lr 5e-5,
×0.01 at iterations 12000 and 15000 of 16000 (6000 for depth only).

The kit's additions enter by composition, as arguments, never imported here (all off in the ``paper``
recipe): ``extra_terms`` added to L_total (the kit's hole terms, :class:`~ddp_lite.method.kit.hole_terms.HoleTerms`),
a ``warp_term`` in place of Eq. 5's cost (its confidence mask, restriction to the holes, census or
gradient cost and texture weights: :func:`~ddp_lite.method.kit.warp_terms.kit_warp_term`) and an occlusion
test per neighbour (``visibility``: :func:`~ddp_lite.method.kit.warp_terms.occlusion_tests`). Other net inputs
are the fit's (:mod:`ddp_lite.method.kit.net_inputs`); auto-stop (:mod:`ddp_lite.method.stopping`), ensembles
(:mod:`ddp_lite.method.kit.ensemble`) and bfloat16 (:func:`ddp_lite.method.runtime.device.use_bf16`) are around it.
"""
from __future__ import annotations

import torch

from .disparity import DisparityTransform
from .config import PaperConfig
from .losses import ConstantTarget, disparity_loss, rgb_loss, warp_loss
from .variants import get_variant
from .warp import Warper

__all__ = ["PaperLoss"]


class PaperLoss:
    """L_total (Eq. 2) of one fit: ``loss(Z_out, I_out)`` → (total, {"disp", "rgb", "warp": term, ...}).

    ``config`` carries γ (``gammas``, None: the variant's) and λz, λI, λw (``lambda_z``, ``lambda_i``,
    ``lambda_w``): a :class:`~ddp_lite.method.paper.config.PaperConfig`. ``target`` (1, 1, H, W) is Z_in and
    ``fit_mask`` (1, 1, H, W) bool its pixels that count; ``rgb`` (1, 3, H, W) is I_in (None without
    colour); ``neighbors`` (image (1, 3, H, W), Camera) pairs seen from ``camera``. The targets' share
    of the work is done here, once per fit.

    What is added to the paper comes in as arguments (None / empty: the paper's loss, nothing else):
    ``warp_term(reference, warped, valid)`` → scalar replaces Eq. 5's cost, for the ConstantTarget I_in
    and one warped image (1, 3, H, W) and valid mask (1, 1, H, W) bool per neighbour; ``visibility``
    holds one occlusion test per neighbour for its warper; each of ``extra_terms`` has
    ``add(Z_out, total, terms)`` → total, and records its terms in ``terms``.
    """

    def __init__(self, variant, config: PaperConfig, transform: DisparityTransform, target: torch.Tensor,
                 fit_mask: torch.Tensor, rgb: torch.Tensor | None = None, camera=None, neighbors=(), device="cpu",
                 *, warp_term=None, visibility=None, extra_terms=()):
        self.config, self.transform = config, transform
        self.w_disp, self.w_rgb, self.w_warp = get_variant(variant).loss_weights(config.gammas)  # γ1, γ2, 1-γ1-γ2
        self.disp_target = ConstantTarget(target, fit_mask)  # Z_in where the depth is valid (holes → 0)
        self.rgb_target = ConstantTarget(rgb) if rgb is not None else None  # I_in, every pixel
        use_warp = self.w_warp > 0
        tests = visibility if visibility is not None else [None] * len(neighbors)
        self.warpers = [Warper(camera, cam, device=device, visibility=test)  # T_nbr^ref
                        for (_, cam), test in zip(neighbors, tests)] if use_warp else []
        self.neighbor_images = [image for image, _ in neighbors] if use_warp else []  # I_nbr
        self.warp_term = warp_term
        self.extra_terms = tuple(extra_terms)

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
            warped, valid = [p[0] for p in pairs], [p[1] for p in pairs]
            if self.warp_term is None:
                terms["warp"] = warp_loss(self.rgb_target, warped, valid, config.lambda_w)  # Eq. 5, mean over the N
            else:  # a cost given from outside (the kit's)
                terms["warp"] = self.warp_term(self.rgb_target, warped, valid)
            total = total + self.w_warp * terms["warp"]  # Eq. 2, + (1 - γ1 - γ2) L_warp
        for extra in self.extra_terms:  # added from outside (the kit's hole terms)
            total = extra.add(disparity, total, terms)
        return total, terms
