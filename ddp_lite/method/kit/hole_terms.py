"""The kit's hole terms of one fit, ready to add to the paper's loss each iteration: their weights
and regions are computed once from the input (the formulas: :mod:`ddp_lite.method.kit.hole_losses`).
"""
from __future__ import annotations

import numpy as np
import torch

from ...classical.guided_fills import NEIGHBOUR_OFFSETS, colorization_affinities
from .hole_losses import affinity_loss, flatness_loss, flatness_region, smoothness_loss, smoothness_weights, step_region
from ..runtime.tensors import to_tensor

__all__ = ["HoleTerms"]


class HoleTerms:
    """The kit's hole terms of one fit: ``add(disparity, total, terms)`` adds each that is on.

    ``config``: a :class:`~ddp_lite.method.config.FitConfig` (its hole-term fields);
    ``free`` (H, W) bool: the pixels no data term constrains (holes and held-out pixels);
    ``disparity`` (H, W) the input disparity, read outside ``free`` (only for ``step_reach``);
    ``rgb_t`` (1, 3, H, W) the colour the edges are measured on (None: no edges); ``rgb``
    (H, W, 3) NumPy, for the colorization affinities (None: no affinity term).
    """

    def __init__(self, config, free: np.ndarray, rgb_t: torch.Tensor | None, rgb: np.ndarray | None,
                 device, disparity: np.ndarray | None = None):
        self.config = config
        H, W = free.shape
        self.smooth_weights = self.flat_weights = self.weight_total = None
        if config.smoothness > 0 or config.flatness > 0:
            guide = rgb_t if rgb_t is not None else torch.zeros(1, 3, H, W, device=device)
            self.smooth_weights = smoothness_weights(guide, to_tensor(free, device).bool(), config.smoothness_edge,
                                                     config.edge_guide)  # (1, 2, H, W)
            # both terms divide by the full weights' sum, also where flatness acts on part of the holes
            self.weight_total = self.smooth_weights.sum()
            if config.step_reach is not None and disparity is not None:
                beside_step = step_region(free, disparity, config.step_reach)
                self.smooth_weights = self.smooth_weights * to_tensor(~beside_step, device)
            self.flat_weights = self.smooth_weights
            if config.flatness > 0 and config.flatness_reach is not None:
                self.flat_weights = self.smooth_weights * to_tensor(flatness_region(free, config.flatness_reach), device)
        self.affinities = self.affinity_region = self.affinity_total = None
        if config.affinity > 0 and rgb is not None:
            self.affinities = torch.from_numpy(colorization_affinities(rgb))[None].to(device)  # (1, 8, H, W)
            self.affinity_region = to_tensor(free, device)  # (1, 1, H, W)
            self.affinity_total = self.affinity_region.sum()

    def add(self, disparity: torch.Tensor, total: torch.Tensor, terms: dict) -> torch.Tensor:
        """``total`` plus each term that is on (weighted), each also recorded in ``terms``."""
        config = self.config
        if config.smoothness > 0:
            terms["smooth"] = smoothness_loss(disparity, self.smooth_weights, self.weight_total)
            total = total + config.smoothness * terms["smooth"]
        if config.flatness > 0:
            terms["flat"] = flatness_loss(disparity, self.flat_weights, self.weight_total)
            total = total + config.flatness * terms["flat"]
        if self.affinities is not None:
            terms["affinity"] = affinity_loss(disparity, self.affinities, NEIGHBOUR_OFFSETS, self.affinity_region,
                                              self.affinity_total)
            total = total + config.affinity * terms["affinity"]
        return total
