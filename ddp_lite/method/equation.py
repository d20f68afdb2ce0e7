"""The objective a fit's config optimises, written out as one equation for a notebook.

The paper's terms (Eq. 2-5, :mod:`ddp_lite.method.paper.total_loss`) come with the weights the
variant gives them; the kit's additions are set apart under a brace marked "not in the paper", so a student
sees at a glance what the recipe in force adds, and how the answer Ẑ is put together from the fit Z
(:math:`\\mathcal{R}_I`: the image-guided solve of ``refine``; fill: the colour-guided fill of ``blend_fill``).
Each kit section writes its own part (``equation()`` beside its settings: the warp term's marks,
:mod:`ddp_lite.method.kit.warp_terms`; the hole terms, :mod:`ddp_lite.method.kit.hole_terms`; the net's
inputs, :mod:`ddp_lite.method.kit.net_inputs`; the answer, :mod:`ddp_lite.method.kit.blend`); this module
puts the paper's terms and those parts together.
"""
from __future__ import annotations

from .paper.variants import get_variant

__all__ = ["loss_equation"]


def _weight(value: float) -> str:
    return f"{value:g}\\,"


def loss_equation(config, variant: str) -> str:
    """The loss ``config`` (a :class:`~ddp_lite.method.config.FitConfig`) optimises for ``variant``,
    as LaTeX for ``IPython.display.Math``: the weighted paper terms, then the kit's terms and the
    net's input, each kit part under a brace "not in the paper".

    Example:
        >>> from ddp_lite.method.config import FitConfig
        >>> print(loss_equation(FitConfig.for_profile("ci", variant="rgbd", recipe="paper"), "rgbd"))
        \\min_\\theta\\ 0.98\\,L^{\\mathrm{disp}} + 0.01\\,L^{\\mathrm{RGB}},\\quad (Z, I) = f_\\theta(\\text{noise})
    """
    spec = get_variant(variant)
    w_disp, w_rgb, w_warp = spec.loss_weights(config.paper.gammas)
    paper = [_weight(w_disp) + "L^{\\mathrm{disp}}"]
    if w_rgb > 0:
        paper.append(_weight(w_rgb) + "L^{\\mathrm{RGB}}")
    if w_warp > 0:
        warp = "L^{\\mathrm{warp}}"
        where = config.warp.equation()
        if where:  # the kit's masks, costs and weights on the warp term
            warp = f"\\underbrace{{L^{{\\mathrm{{warp}}}}_{{\\mathrm{{{', '.join(where)}}}}}}}_{{\\text{{not in the paper}}}}"
        paper.append(_weight(w_warp) + warp)
    kit = config.holes.equation()
    loss = " + ".join(paper)
    if kit:
        loss += " + \\underbrace{" + " + ".join(kit) + "}_{\\text{not in the paper}}"
    outputs = "(Z, I)" if spec.uses_rgb else "Z"
    in_paper, added = config.net_inputs.equation(config.paper.noise_channels, spec.uses_rgb)
    net_input = ", ".join(in_paper + (["\\underbrace{" + ", ".join(added) + "}_{\\text{not in the paper}}"]
                                      if added else []))
    equation = f"\\min_\\theta\\ {loss},\\quad {outputs} = f_\\theta({net_input})"
    answer = config.combination.equation()
    if answer:  # fits and a fill, blended, the fit made sharp first
        equation += f",\\quad \\underbrace{{\\hat Z = {answer}}}_{{\\text{{not in the paper}}}}"
    return equation
