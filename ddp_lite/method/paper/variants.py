"""The three DDP variants (paper Sec. 3.3, Table 2): one record each, looked up in one place.

- ``"d"``: disparity only. The net outputs 1 channel; L = L_disp.
- ``"rgbd"``: disparity and colour. The net outputs RGBD (4 channels); L = γ1 L_disp + γ2 L_rgb.
- ``"rgbd+warp"``: plus photo-consistency with calibrated neighbours (a camera and at least
  one neighbour view); L = γ1 L_disp + γ2 L_rgb + (1 - γ1 - γ2) L_warp.

The variants are the same loop with different loss weights; everything that differs between
them is a field of :class:`Variant`, so nothing else branches on the name.
"""
from __future__ import annotations

from dataclasses import dataclass

__all__ = ["Variant", "VARIANTS", "get_variant"]


@dataclass(frozen=True)
class Variant:
    """What one DDP variant is: its loss terms, its net's output, what it needs, its schedule.

    Example:
        >>> [round(w, 6) for w in get_variant("rgbd+warp").loss_weights()]
        [0.96, 0.02, 0.02]
    """

    name: str
    uses_rgb: bool  # the net outputs RGBD and fits the reference colour (L_rgb)
    needs_neighbors: bool  # the warp term L_warp: a reference camera and calibrated neighbours
    gammas: tuple[float, float] = (1.0, 0.0)  # the paper's default (γ1, γ2) for this variant
    paper_iterations: int = 16000  # the paper's iteration count (supplement)

    @property
    def out_channels(self) -> int:
        """Channels of the net's output: 4 (disparity, R, G, B) or 1 (disparity)."""
        return 4 if self.uses_rgb else 1

    @property
    def depth_only(self) -> bool:
        """True for the disparity-only variant (the profiles give it its own iteration count)."""
        return not self.uses_rgb

    def loss_weights(self, gammas=None) -> tuple[float, float, float]:
        """(w_disp, w_rgb, w_warp) of L_total; ``gammas`` (γ1, γ2) overrides the paper's pair."""
        if not self.uses_rgb:
            return 1.0, 0.0, 0.0
        g1, g2 = gammas or self.gammas
        return g1, g2, (1.0 - g1 - g2 if self.needs_neighbors else 0.0)


# γ: (0.96, 0.02) for multi-view data (Tanks and Temples), (0.98, 0.01) otherwise (supplement).
# Depth only re-opens holes if run longer than 6000 iterations (paper Sec. 4).
_RECORDS = (
    Variant("d", uses_rgb=False, needs_neighbors=False, paper_iterations=6000),
    Variant("rgbd", uses_rgb=True, needs_neighbors=False, gammas=(0.98, 0.01)),
    Variant("rgbd+warp", uses_rgb=True, needs_neighbors=True, gammas=(0.96, 0.02)),
)
_BY_NAME = {v.name: v for v in _RECORDS}
VARIANTS = tuple(_BY_NAME)  # ("d", "rgbd", "rgbd+warp"): the names, in the paper's order


def get_variant(variant: str | Variant) -> Variant:
    """The :class:`Variant` named ``variant`` (a Variant is returned as is); ``ValueError`` otherwise."""
    if isinstance(variant, Variant):
        return variant
    if not isinstance(variant, str) or variant not in _BY_NAME:
        raise ValueError(f"variant must be one of {VARIANTS}, got {variant!r}")
    return _BY_NAME[variant]
