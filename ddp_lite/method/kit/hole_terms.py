"""The kit's hole terms of one fit, their settings (:class:`HoleConfig`) and the terms ready to add to
the paper's loss each iteration (:class:`HoleTerms`): their weights and regions are computed once
from the input (the formulas: :mod:`ddp_lite.method.kit.hole_losses`).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import torch

from ...classical.guided_fills import NEIGHBOUR_OFFSETS, colorization_weights
from ...core.checks import check_choice, check_real
from ...core.settings import Settings
from .hole_losses import (EDGE_GUIDES, affinity_loss, flatness_loss, flatness_region, smoothness_loss,
                          smoothness_weights, step_region)
from ..runtime.tensors import to_tensor

__all__ = ["HoleConfig", "HoleTerms"]


@dataclass(frozen=True)
class HoleConfig(Settings):
    """The kit's terms on the disparity in the holes (7 fields; each weight 0: off, the paper)."""

    smoothness: float = 0.0  # weight of an edge-aware second-order smoothness of disparity in the holes
    smoothness_edge: float = 10.0  # how strongly colour edges relax both hole terms: exp(-edge · |∇I|)
    edge_guide: str = "grey"  # |∇I| of the grey image, "rgb": the largest over the three channels, or "structure"
    flatness: float = 0.0  # weight of an edge-aware first-order smoothness in the holes
    affinity: float = 0.0  # weight of the colorization energy in the holes (hole_losses.affinity_loss)
    flatness_reach: float | None = None  # enclosed holes: that term only within this many px of valid depth (None: everywhere)
    step_reach: float | None = None  # hole terms off within this many px of a depth step in the valid input (None: on)

    def validate(self) -> None:
        check_choice(self.edge_guide, "config.edge_guide", EDGE_GUIDES)
        for name in ("smoothness", "flatness", "affinity", "smoothness_edge"):
            check_real(getattr(self, name), f"config.{name}", 0.0)
        for name in ("flatness_reach", "step_reach"):
            if getattr(self, name) is not None:
                check_real(getattr(self, name), f"config.{name}", 0.0)

    def describe(self) -> str:
        """These terms' part of a recipe's one-line description (``kit.recipes.describe_method``); "" if off."""
        guide = {"grey": "|∇grey|", "rgb": "max over R, G, B of |∇I|", "structure": "|∇ structure of grey|"}
        return ((f", hole curvature weight {self.smoothness:g}" if self.smoothness else "")
                + (f", hole flatness weight {self.flatness:g}" if self.flatness else "")
                + (f" (in enclosed holes only within {self.flatness_reach:g} px of valid depth)"
                   if self.flatness and self.flatness_reach is not None else "")
                + (f" (relaxed at colour edges by exp(-{self.smoothness_edge:g}·" + guide[self.edge_guide] + "))"
                   if self.smoothness or self.flatness else ""))

    def equation(self) -> list[str]:
        """These terms of the loss a config optimises (``method.equation``), weighted, LaTeX; [] if off."""
        return [f"{weight:g}\\,{term}" for weight, term in ((self.smoothness, "L^{\\mathrm{curv}}_{w}"),
                                                           (self.flatness, "L^{\\mathrm{flat}}_{w}"),
                                                           (self.affinity, "L^{\\mathrm{aff}}")) if weight > 0]


class HoleTerms:
    """The kit's hole terms of one fit: ``add(disparity, total, terms)`` adds each that is on.

    ``config``: the terms' :class:`HoleConfig`;
    ``free`` (H, W) bool: the pixels no data term constrains (holes and held-out pixels);
    ``disparity`` (H, W) the input disparity, read outside ``free`` (only for ``step_reach``);
    ``rgb_t`` (1, 3, H, W) the colour the edges are measured on (None: no edges); ``rgb``
    (H, W, 3) NumPy, for the colorization affinities (None: no affinity term).
    """

    def __init__(self, config: HoleConfig, free: np.ndarray, rgb_t: torch.Tensor | None, rgb: np.ndarray | None,
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
            weights, _ = colorization_weights(rgb.astype(np.float64))  # rgb: the fit's, checked
            self.affinities = torch.from_numpy(weights.astype(np.float32))[None].to(device)  # (1, 8, H, W)
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
