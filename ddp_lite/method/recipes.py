"""Recipes: *which method* a fit runs, apart from *how big* it is (the profile).

A profile (``ci``, ``class``, ``paper``; ``DDP_PROFILE``) sets the size and the budget. A recipe
(``DDP_RECIPE``, or ``recipe=`` of :meth:`FitConfig.for_profile`) says what is optimised:

- ``paper``: the paper's method and nothing else: L_disp, L_rgb, L_warp (Eq. 2-5,
  :mod:`ddp_lite.method.paper_method`) with their weights, from the fixed noise input; no hole terms, no
  coordinates or image in the input.
- ``kit`` (the default): the paper's losses *plus* what the kit found to help at laptop sizes, per
  profile (:data:`KIT_AT`): the curvature and flatness terms in the holes, relaxed at colour edges
  (:mod:`ddp_lite.method.hole_terms`); the pixel coordinates and the blurred colour image as the net's
  input (:mod:`ddp_lite.method.nets`); a share of a colour-guided fill of the input mixed into the result
  where the variant sees colour (:mod:`ddp_lite.method.blend`). At ``paper`` it is the
  paper's method.
- ``photo``: for real photographs, the mean of a ``kit`` fit, a ``paper`` fit and the input's
  colour-guided fill (two fits, :mod:`ddp_lite.method.blend`): ahead of each on the real Middlebury
  pair, behind ``kit`` on the rendered scenes.

Every profile runs with every recipe, so ``FitConfig.for_profile("ci", recipe="paper")`` is the
paper's method in seconds. The quality study's other recipes are :data:`STUDY`. The numbers
quoted are DDP's mean hole error over the quality suite as a multiple of the best classical fill
of each case (``benchmarks/bench_quality.py``); their history is ``docs/quality_study.md``.
"""
from __future__ import annotations

from dataclasses import dataclass, field

from ..core.checks import env_choice, named_choice

__all__ = ["Recipe", "RECIPES", "KIT_AT", "STUDY", "ENV_VAR", "DEFAULT", "current_recipe_name", "get_recipe",
           "describe_method"]

ENV_VAR = "DDP_RECIPE"
DEFAULT = "kit"


@dataclass(frozen=True)
class Recipe:
    """A named method: ``FitConfig`` overrides on top of a profile's size and budget, and why.

    :meth:`settings` stacks, in order: the ``base`` recipe's settings, this recipe's settings for
    the profile (``at``, by profile name), then ``overrides`` (for every profile).
    """

    name: str
    overrides: dict = field(default_factory=dict)
    why: str = ""
    at: dict = field(default_factory=dict)  # profile name → overrides there
    base: str | None = None  # the recipe these settings are applied on top of

    def settings(self, profile: str) -> dict:
        """The ``FitConfig`` fields this recipe sets at the profile named ``profile``."""
        values = dict(RECIPES[self.base].settings(profile)) if self.base else {}
        values.update(self.at.get(profile, {}))
        values.update(self.overrides)
        return values


# The kit's additions, per profile (FitConfig fields), each with what it bought on the quality suite when it
# came in (multiples of the best classical fill, seeds 0 and 1; docs/quality_study.md has each step).
KIT_AT = {
    "ci": dict(
        smoothness=1.0,  # curvature in the holes: a hole far from valid pixels does not bend (5.4× → 2.4×)
        smoothness_edge=100.0,  # hole terms relaxed at colour edges, exp(-100·|∇grey|) (alone 1.41×; 300: 1.67×)
        flatness=0.6,  # first order in the holes: a hole at the border levels off (with edge 100: 1.53× → 1.38×)
        image_input=1.0,  # the colour image in the net's input puts depth edges at colour edges (2.24× → 1.53×)
        image_blur=0.5,  # ... blurred by 0.5 px, class's 1 px at ci's half size (1 px: 1.73×, none: 1.93×)
        # class's quarter of the input's colour-guided fill (variants with colour): the real pair 1.330× → 1.201×
        # (rgbd), 1.315× → 1.188× (with the warp term); the rendered scenes' geometric mean 1.246× → 1.210× (rgbd),
        # 1.194× → 1.178× (their plain mean 1.64× → 1.58×: the bilateral solver costs on desk/blobs at 48×64)
        blend_fill=0.25,
    ),
    "class": dict(
        smoothness=1.0,  # curvature in the holes, as at ci (1.34× → 1.22× when it came in)
        smoothness_edge=300.0,  # with the image in the input, act only where colour is flat (0.875× → 0.825×)
        flatness=0.6,  # first order in the holes: levels off at the border (1.26× → 1.15×; 0.3 and 1 worse)
        net_input="meshgrid",  # the pixel coordinates instead of noise, DIP's input for large holes (1.15× → 0.99×)
        noise_channels=2,  # ... x and y only (with 14 noise channels too: 1.03×)
        image_input=1.0,  # the colour image in the net's input puts depth edges at colour edges (0.904× → 0.875×)
        image_blur=1.0,  # ... blurred by 1 px (none: 0.880×, 2 px: 0.873× against 0.869× on one seed)
        bf16=None,  # the net in bfloat16 where the CPU has it natively: 0.825× vs 0.857× in fp32, 20.4 vs 23.0 s
        # a quarter of the input's fill (the mean of the colorization and bilateral-solver fills) in the result
        # (variants with colour): on the real Middlebury pair 1.227× → 1.123× (rgbd), 1.205× → 1.102× (with the
        # warp term); the rendered scenes 0.852× → 0.867× (rgbd, two seeds), 0.833× → 0.853× (with the warp term)
        blend_fill=0.25,
    ),
    "paper": {},  # at the paper's size, the paper's method
}

RECIPES = {
    "kit": Recipe("kit", {}, "the paper's losses plus the kit's hole terms and net inputs, which fill large holes "
                             "better at small sizes (KIT_AT: what each profile adds, and why)", at=KIT_AT),
    # the kit's settings at the profile with every addition switched off: what stays acts on nothing
    # (the colour-edge strength, the blur of an image that is not in the input) but bf16 at class, the
    # precision the net runs in, not what it optimises
    "paper": Recipe("paper", dict(smoothness=0.0, flatness=0.0, image_input=0.0, fill_input=0.0, net_input="noise",
                                  noise_channels=16, blend_paper=False, blend_fill=0.0),
                    "the paper's losses (Eq. 2-5) from its 16-channel noise input, nothing added", base="kit"),
    # for real photographs: the two recipes and the colour-guided fill err in different places there (the
    # kit on occlusions, the paper on blob holes, the fill where colour misleads), and their mean beats
    # each (docs/real_data.md); on the rendered scenes it costs
    "photo": Recipe("photo", dict(blend_paper=True, blend_weight=0.5, blend_fill=1 / 3),
                    "for real photographs: the mean of the kit's fit, the paper's and a colour-guided fill, two fits",
                    base="kit"),
}


def current_recipe_name() -> str:
    """The recipe ``DDP_RECIPE`` names (default ``kit``)."""
    return env_choice(ENV_VAR, DEFAULT, RECIPES)


def get_recipe(name: str | Recipe | None = None) -> Recipe:
    """The named recipe, or the one ``DDP_RECIPE`` selects; a :class:`Recipe` is returned as is."""
    if isinstance(name, Recipe):
        return name
    return named_choice(name, RECIPES, "recipe", current_recipe_name)


def describe_method(settings: dict) -> str:
    """What ``settings`` (as :meth:`Recipe.settings` gives) add to the paper's method, for one line
    of a notebook's first cell: "" for the paper's method."""
    smoothness, flatness = settings.get("smoothness", 0.0), settings.get("flatness", 0.0)
    reach, edge = settings.get("flatness_reach"), settings.get("smoothness_edge", 10.0)
    noise_channels, ensemble = settings.get("noise_channels", 16), settings.get("ensemble", 1)
    return ((f", hole curvature weight {smoothness:g}" if smoothness else "")
            + (f", hole flatness weight {flatness:g}" if flatness else "")
            + (f" (in enclosed holes only within {reach:g} px of valid depth)"
               if flatness and reach is not None else "")
            + (f" (relaxed at colour edges by exp(-{edge:g}·"
               + {"grey": "|∇grey|", "rgb": "max over R, G, B of |∇I|", "structure": "|∇ structure of grey|"}[
                   settings.get("edge_guide", "grey")] + "))"
               if smoothness or flatness else "")
            + (", input: the pixel coordinates" + (" + noise" if noise_channels > 2 else "")
               if settings.get("net_input", "noise") == "meshgrid" else "")
            + (f" + the colour image (blurred, σ {settings.get('image_blur', 1.0):g} px; not for depth-only)"
               if settings.get("image_input", 0.0) else "")
            + (", the warp term only where the neighbour can see" if settings.get("warp_occlusion") else "")
            + (f", mean of {ensemble} fits" if ensemble > 1 else "")
            + ((", blended with the paper recipe's fit, " + ("weight from a held-out ring" if settings.get("blend_weight", 0.5) is None
               else f"weight {settings.get('blend_weight', 0.5):g}")) if settings.get("blend_paper") else "")
            + (", and with the input's colour-guided fill (colorization and bilateral solver, averaged), " + (
                "its share (0–0.5) chosen on held-out blobs of the valid depth" if settings["blend_fill"] is None
                else f"share {settings['blend_fill']:.3g}") + " (not for depth-only)"
               if settings.get("blend_fill", 0.0) != 0 else ""))


# The quality study's other recipes (``benchmarks/bench_quality.py --recipes NAME``): name → FitConfig
# overrides on top of a profile's ``kit`` config. The recipes of earlier passes pin what
# they ran where `class` has changed since, or might (no colour image in the net's input: NO_IMAGE;
# colour edges on grey: GREY; at the edge-strength study's strength 100: E100; at 10: EDGE10; the noise
# input too: NOISE). The `ci-` recipes are `ci`'s own; those of the colour-image study pin its recipe then
# (strength 10, no flatness term: CI7).
NO_IMAGE = dict(image_input=0.0)
GREY = dict(edge_guide="grey", **NO_IMAGE)
E100 = dict(smoothness_edge=100.0)
EDGE10 = dict(smoothness_edge=10.0, **GREY)
NOISE = dict(net_input="noise", noise_channels=16, **EDGE10)
IMAGE = dict(image_input=1.0, image_blur=1.0)  # class's colour image in the input (the colour-image study)
CI7 = dict(smoothness_edge=10.0, flatness=0.0)  # ci until the `ci` catch-up: strength 10, no flatness term
STUDY = {
    "kit-ens2": dict(ensemble=2),  # real data first: the mean of two fits, ...
    "kit-ens3": dict(ensemble=3),  # ... of three,
    "patience100": dict(patience=100),  # ... a longer plateau before the rate cut and the stop,
    "e100": dict(smoothness_edge=100.0),  # ... colour edges at strength 100 (textured photos),
    "blur2": dict(image_blur=2.0),  # ... the colour image in the input blurred by 2 px,
    "fillin": dict(fill_input=1.0),  # ... a colorization fill of the input disparity as one more input channel,
    "affinity": dict(affinity=1.0, smoothness=0.0, flatness=0.0),  # ... the colorization energy as the hole term,
    "no-image": dict(**GREY, **E100),  # class before the colour-image study: no colour image in the net's input
    "image-e100": dict(**IMAGE, **E100),  # the colour-image study: the colour image in the input, at strength 100 ...
    "image-sharp": dict(image_input=1.0, image_blur=0.0, **E100),  # ... unblurred
    "image-blur2": dict(image_input=1.0, image_blur=2.0, **E100),  # ... blurred more
    "image0.3": dict(image_input=0.3, image_blur=1.0, **E100),  # ... at a third of the coordinates' scale
    "image-patience100": dict(patience=100, **IMAGE, **E100),  # ... with a longer plateau
    "image-dip1200": dict(auto_stop=False, iterations=1200, lr_milestones=(), **IMAGE, **E100),  # ... DIP's schedule
    "image-e1000": dict(smoothness_edge=1000.0, **IMAGE),  # the image at other strengths (the new class: 300)
    "ci-no-image": dict(**GREY, **CI7),  # ci before the colour-image study
    "ci-image-sharp": dict(image_input=1.0, image_blur=0.0, **CI7),  # ci with the colour image unblurred, ...
    "ci-image-blur1": dict(image_input=1.0, image_blur=1.0, **CI7),  # ... blurred by 1 px (ci keeps 0.5)
    "ci-e10": CI7,  # ci after the colour-image study (the colour image, σ 0.5 px); then, the `ci` catch-up:
    "ci-e3": dict(smoothness_edge=3.0, flatness=0.0),  # its colour-edge strength, without the flatness term
    "ci-e30": dict(smoothness_edge=30.0, flatness=0.0),
    "ci-e100": dict(smoothness_edge=100.0, flatness=0.0),
    "ci-e300": dict(smoothness_edge=300.0, flatness=0.0),
    "ci-e1000": dict(smoothness_edge=1000.0, flatness=0.0),
    "ci-e100-meshgrid": dict(smoothness_edge=100.0, flatness=0.0, net_input="meshgrid", noise_channels=2),
    "ci-e100-smooth2": dict(smoothness_edge=100.0, flatness=0.0, smoothness=2.0),
    "ci-flat0.3": dict(flatness=0.3),  # strength 100 with the flatness term at 0.3 (ci now: 0.6)
    "fp32": dict(bf16=False),  # class in float32 (it runs the net in bfloat16 where the CPU has it)
    "image-warp-w10": dict(gammas=(0.88, 0.02)),  # rgbd+warp with the warp term at 0.10 (class's recipe)
    "image-flat0.3": dict(flatness=0.3),  # class's recipe with the flatness term at 0.3, ...
    "image2": dict(image_input=2.0),  # ... the colour image at twice the coordinates' scale,
    "image-wide": dict(channels=(32, 64, 128, 256, 512)),  # ... the paper's widths,
    "image-smooth2": dict(smoothness=2.0),  # ... curvature weight 2
    "warp-patience100": dict(patience=100),  # ... a longer plateau (run with rgbd+warp)
    "lr5e-3": dict(lr=5e-3),  # the flatness-reach study, on class's recipe: Adam's rate halved, ...
    "lr2e-2": dict(lr=2e-2),  # ... doubled,
    "lz1": dict(lambda_z=1.0),  # ... L_disp all L1 (the paper: 0.8 L1 + 0.2 SSIM),
    "reach4": dict(flatness_reach=4.0),  # ... the flatness term only at the border and 4 px into enclosed holes,
    "rgb0.05": dict(gammas=(0.95, 0.05)),  # ... the colour term at 0.05 (the paper's rgbd: 0.01),
    "reach4-rgb0.05": dict(flatness_reach=4.0, gammas=(0.95, 0.05)),  # ... both,
    "margin1.1": dict(disparity_margin=1.1),  # ... the disparity range 1.1× around the valid depth's (default 1.25)
    "reach4-margin1.1": dict(flatness_reach=4.0, disparity_margin=1.1),  # the rgbd+warp study: the two together; then rgbd+warp's own:
    "warp0.05": dict(gammas=(0.93, 0.02)),  # ... the warp term at 0.05 (the paper's, and class's: 0.02), ...
    "warp0.07": dict(gammas=(0.91, 0.02)),  # ... 0.07,
    "warp-rgb0.05": dict(gammas=(0.93, 0.05)),  # ... the colour term at 0.05 beside the warp term's 0.02,
    "warp-lw0.85": dict(lambda_w=0.85),  # ... L_warp 85 % SSIM (Monodepth2's share; the paper: 50 %),
    "warp-flat1": dict(flatness=1.0),  # ... the flatness term at 1 (class: 0.6)
    "edge10": EDGE10,  # class before the edge-strength study
    "edge30": dict(smoothness_edge=30.0, **GREY),
    "e100-rgb": dict(edge_guide="rgb", **NO_IMAGE, **E100),  # colour edges measured on R, G, B (tried, not kept)
    "edge300": dict(smoothness_edge=300.0, **GREY),
    "edge1000": dict(smoothness_edge=1000.0, **GREY),
    "warp-w10": dict(gammas=(0.88, 0.02), **EDGE10),  # rgbd+warp with the warp term at 0.10 instead of 0.02
    "warp-w25": dict(gammas=(0.73, 0.02), **EDGE10),  # ... at 0.25
    "e100-flat0.3": dict(flatness=0.3, **GREY, **E100),  # edge 100 on grey with other hole-term weights
    "e100-flat1": dict(flatness=1.0, **GREY, **E100),
    "e100-smooth0.5": dict(smoothness=0.5, **GREY, **E100),
    "e100-smooth2": dict(smoothness=2.0, **GREY, **E100),
    "paper-losses": dict(smoothness=0.0, flatness=0.0, bf16=False, channels=(32, 64, 128, 256, 512), **NOISE),  # class before the quality study
    "paper-net": dict(channels=(32, 64, 128, 256, 512), flatness=0.0, **NOISE),  # class before the width study (one 32-512 fit)
    "curvature-ens3": dict(flatness=0.0, ensemble=3, **NOISE),  # class before the flatness study: the mean of three, no flatness
    "one-fit-curvature": dict(flatness=0.0, **NOISE),  # one fit of that recipe
    "flat0.3": dict(flatness=0.3, **NOISE),  # the flatness study: the flatness term at 0.3 instead of 0.6
    "flat1": dict(flatness=1.0, **NOISE),  # ... at 1
    "ens3": dict(ensemble=3, **NOISE),  # the mean of three fits of the flatness study's class recipe
    "noise-input": NOISE,  # class before the input study: the paper's noise input
    "meshgrid+noise": dict(net_input="meshgrid", noise_channels=16, **EDGE10),  # the coordinates and 14 noise channels
    "quarter-ens4": dict(channels=(8, 16, 32, 64, 128), ensemble=4, flatness=0.0, **NOISE),  # chosen on 8 cases, failed on the others
    "ema": dict(average_outputs=0.9),
    "cosine": dict(schedule="cosine"),
    "lr3e-3": dict(lr=3e-3),
    "lr3e-2": dict(lr=3e-2),
    "it300": dict(iterations=300),
    "pool": dict(down="pool"),
    "nearest": dict(up="nearest"),
    "zeros": dict(pad="zeros"),
    "jitter": dict(reg_noise_std=1 / 30),
    "margin1": dict(disparity_margin=1.0),
    "margin2": dict(disparity_margin=2.0),
    "l1only": dict(lambda_z=1.0),
    "rgb10": dict(gammas=(0.9, 0.1)),
    "autostop": dict(auto_stop=True, patience=50, plateau_decays=1, iterations=600, lr_milestones=()),
    "constant": dict(lr_milestones=()),
    "smooth0.1": dict(smoothness=0.1),
    "smooth1": dict(smoothness=1.0),
    "smooth10": dict(smoothness=10.0),
    "smooth3": dict(smoothness=3.0),
    "smooth0.3": dict(smoothness=0.3),
    "smooth1-edge0": dict(smoothness=1.0, smoothness_edge=0.0),
    "smooth1-edge30": dict(smoothness=1.0, smoothness_edge=30.0),
    "smooth1-it300": dict(smoothness=1.0, iterations=300),
    "smooth1-lr3e-3": dict(smoothness=1.0, lr=3e-3),
    "smooth1-ens3": dict(smoothness=1.0, ensemble=3),
    "holdout-blobs": dict(holdout="blobs"),
    "step3": dict(step_reach=3.0),  # real data: the hole terms off within 3 px of a depth step of the input,
    "step6": dict(step_reach=6.0),  # ... within 6 px (occlusion bands are 2-10 px wide at 125×185)
    "blend-ring": dict(blend_paper=True, blend_weight=None),  # the photo recipe's blend, its weight from a held-out ring
    "occl": dict(warp_occlusion=True),  # the warp term skips the pixels the neighbour cannot see (method.visibility)
    "fill-chosen": dict(blend_fill=None),  # the fill's share (0-0.5) chosen on held-out blobs of the valid depth
}
# every recipe above ran before `class` mixed a share of the colorization fill into its result
STUDY = {name: {"blend_fill": 0.0, **overrides} for name, overrides in STUDY.items()}
