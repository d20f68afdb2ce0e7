"""The objective a fit's config optimises, written out as one equation for a notebook.

The paper's terms (Eq. 2-5, :mod:`ddp_lite.method.paper.total_loss`) come with the weights the
variant gives them; the kit's additions (:mod:`ddp_lite.method.kit.hole_terms`, the net inputs of
:mod:`ddp_lite.method.paper.nets`) are set apart under a brace marked "not in the paper", so a student
sees at a glance what the recipe in force adds, and how the answer Ẑ is put together from the fit Z
(:math:`\\mathcal{R}_I`: the image-guided solve of ``refine``; fill: the colour-guided fill of ``blend_fill``).
Reads only the config's fields.
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
        cost = config.warp.warp_cost  # method.kit.warp_cost; "intensity" is the paper's
        where = [name for name, on in (("visible", config.warp.warp_occlusion),  # method.visibility
                                       ("confident", config.warp.warp_confidence),  # method.warp_confidence
                                       ("holes", config.warp.warp_reach is not None),  # kit.warp_terms.warp_region
                                       (cost, cost != "intensity"),
                                       ("textured", config.warp.warp_texture),
                                       ("min over views", config.warp.warp_combine == "min"))
                 if on]
        if where:  # the kit's masks, costs and weights on the warp term
            warp = f"\\underbrace{{L^{{\\mathrm{{warp}}}}_{{\\mathrm{{{', '.join(where)}}}}}}}_{{\\text{{not in the paper}}}}"
        paper.append(_weight(w_warp) + warp)
    kit = []
    if config.holes.smoothness > 0:
        kit.append(_weight(config.holes.smoothness) + "L^{\\mathrm{curv}}_{w}")
    if config.holes.flatness > 0:
        kit.append(_weight(config.holes.flatness) + "L^{\\mathrm{flat}}_{w}")
    if config.holes.affinity > 0:
        kit.append(_weight(config.holes.affinity) + "L^{\\mathrm{aff}}")
    loss = " + ".join(paper)
    if kit:
        loss += " + \\underbrace{" + " + ".join(kit) + "}_{\\text{not in the paper}}"
    outputs = "(Z, I)" if spec.uses_rgb else "Z"
    in_paper = ["\\text{noise}"] if config.net_inputs.net_input != "meshgrid" or config.paper.noise_channels > 2 else []
    added = ["u, v"] if config.net_inputs.net_input == "meshgrid" else []
    if spec.uses_rgb and config.net_inputs.image_input > 0:
        added.append(f"G_{{{config.net_inputs.image_blur:g}}} * I_{{\\mathrm{{in}}}}")
    if config.net_inputs.fill_input > 0:
        added.append("\\text{fill}(Z_{\\mathrm{in}})")
    net_input = ", ".join(in_paper + (["\\underbrace{" + ", ".join(added) + "}_{\\text{not in the paper}}"]
                                      if added else []))
    equation = f"\\min_\\theta\\ {loss},\\quad {outputs} = f_\\theta({net_input})"
    paper_fit, fill, refine = (config.combination.blend_paper, config.combination.blend_fill,
                               config.combination.refine)
    if paper_fit or fill != 0 or refine:  # fits and a fill, blended (method.blend), the fit made sharp first
        w = config.combination.blend_weight if paper_fit else 1.0
        z, z_paper = "Z", "Z_{\\mathrm{paper}}"
        if fill is None:  # the share chosen on held-out depth
            fits = z if w == 1.0 else (f"(w^* {z} + (1 - w^*)\\,{z_paper})" if w is None else
                                       f"({w:.3g}\\,{z} + {1 - w:.3g}\\,{z_paper})")
            fits = f"\\mathcal{{R}}_I({fits})" if refine else fits
            mix = f"(1 - f^*)\\,{fits} + f^*\\,\\mathrm{{fill}}(Z_{{\\mathrm{{in}}}})"
        elif w is None:
            mix = f"w^* {z} + (1 - w^*)\\,{z_paper}"
            mix = f"\\mathcal{{R}}_I({mix})" if refine else mix
            if fill > 0:
                mix = f"{1 - fill:.3g}\\,({mix}) + {fill:.3g}\\,\\mathrm{{fill}}(Z_{{\\mathrm{{in}}}})"
        elif refine:  # the solve acts on the fits' blend, then the fill is mixed in
            fits = z if w == 1.0 else f"{w:.3g}\\,{z} + {1 - w:.3g}\\,{z_paper}"
            mix = f"\\mathcal{{R}}_I({fits})"
            if fill > 0:
                mix = f"{1 - fill:.3g}\\,{mix} + {fill:.3g}\\,\\mathrm{{fill}}(Z_{{\\mathrm{{in}}}})"
        else:
            mix = " + ".join(f"{share:.3g}\\,{term}" for share, term in
                             (((1 - fill) * w, z), ((1 - fill) * (1 - w), z_paper),
                              (fill, "\\mathrm{fill}(Z_{\\mathrm{in}})")) if share > 0)
        equation += f",\\quad \\underbrace{{\\hat Z = {mix}}}_{{\\text{{not in the paper}}}}"
    return equation
