"""Recipes: *which method* a fit runs, apart from *how big* it is (the profile).

A profile (``ci``, ``class``, ``paper``; ``DDP_PROFILE``) sets the size and the budget. A recipe
(``DDP_RECIPE``, or ``recipe=`` of :meth:`FitConfig.for_profile`) says what is optimised:

- ``paper``: the paper's method and nothing else: L_disp, L_rgb, L_warp (Eq. 2-5,
  :mod:`ddp_lite.method.paper.total_loss`) with their weights, from the fixed noise input; no hole terms, no
  coordinates or image in the input.
- ``kit`` (the default): the paper's losses *plus* what the kit found to help at laptop sizes, per
  profile (:data:`KIT_AT`): the curvature and flatness terms in the holes, relaxed at colour edges
  (:mod:`ddp_lite.method.kit.hole_terms`); the pixel coordinates and the blurred colour image as the net's
  input (:mod:`ddp_lite.method.paper.nets`); a share of a colour-guided fill of the input mixed into the result
  where the variant sees colour (:mod:`ddp_lite.method.kit.blend`). At ``paper`` it is the
  paper's method.
- ``photo``: for real photographs, the ``kit`` fit without its hole terms (:data:`PHOTO_HOLE_TERMS`),
  made sharp by an image-guided edge-aware solve toward it (``refine``: the fast bilateral solver of
  :mod:`ddp_lite.classical.full_resolution` at the fit's own size, averaged over four smoothness settings),
  with the kit's share of the colour-guided fill: one fit, the kit's best on the real suite's cases, SGBM's
  depth declared a stereo matcher's (its numbers: ``docs/results.md``; how it was chosen:
  ``docs/studies/real_suite.md``). ``ddp-lite complete`` runs one such solve at the photo's full size instead.
  For a stereo matcher's depth, ``depth_source="stereo"`` (``FitConfig`` field; ``complete --depth-source``):
  the solves and the fill do not read the rim of its holes, which the matcher often got wrong, and reach
  twice as far (:mod:`ddp_lite.method.kit.blend`).

Every profile runs with every recipe, so ``FitConfig.for_profile("ci", recipe="paper")`` is the
paper's method in seconds. The quality study's other recipes are ``benchmarks/study_recipes.py``;
what each addition bought on the quality suite (``benchmarks/bench_quality.py``) is
``docs/studies/quality_study.md``.
"""
from __future__ import annotations

from dataclasses import dataclass, field

from ...core.checks import env_choice, named_choice
from ..paper.config import PaperConfig
from .blend import CombinationConfig
from .hole_terms import HoleConfig
from .net_inputs import NetInputConfig
from .warp_terms import WarpConfig

__all__ = ["Recipe", "RECIPES", "KIT_AT", "PHOTO_HOLE_TERMS", "ENV_VAR", "DEFAULT", "FOR_PHOTOGRAPHS",
           "current_recipe_name", "get_recipe", "describe_method"]

ENV_VAR = "DDP_RECIPE"
DEFAULT = "kit"
# The recipe the kit recommends for real photographs: the best of the recipes on the real suite's cases
# (docs/results.md). What shows the kit's answer on real scenes (notebook 06's Table 6) reads it here.
FOR_PHOTOGRAPHS = "photo"


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
    purpose: str = ""  # who it is for, in a few words, for the line a notebook prints

    def settings(self, profile: str) -> dict:
        """The ``FitConfig`` fields this recipe sets at the profile named ``profile``."""
        values = dict(RECIPES[self.base].settings(profile)) if self.base else {}
        values.update(self.at.get(profile, {}))
        values.update(self.overrides)
        return values

    def describe(self, profile) -> str:
        """One line for a notebook's first cell: this recipe's purpose, then what it runs at ``profile`` (a name
        or a :class:`~ddp_lite.method.profiles.Profile`), written from :meth:`settings`: the paper's losses and
        each addition with its weight, or "nothing added"."""
        name = profile if isinstance(profile, str) else profile.name
        added = describe_method(self.settings(name))
        return (f"recipe '{self.name}'" + (f" ({self.purpose})" if self.purpose else "") + f" at '{name}': "
                "the paper's losses (Eq. 2-5)" + (added if added else " from its 16-channel noise input, nothing added"))


# The kit's additions, per profile (FitConfig fields), each with why; what each bought on the quality suite,
# step by step: docs/studies/quality_study.md.
KIT_AT = {
    "ci": dict(
        smoothness=1.0,  # curvature in the holes: a hole far from valid pixels does not bend
        smoothness_edge=100.0,  # the hole terms relaxed at colour edges, exp(-100·|∇grey|)
        flatness=0.6,  # first order in the holes: a hole at the border levels off
        image_input=1.0,  # the colour image in the net's input puts depth edges at colour edges
        image_blur=0.5,  # ... blurred by 0.5 px, class's 1 px at ci's half size
        blend_fill=0.25,  # a quarter of the input's colour-guided fill in the result (variants with colour)
    ),
    "class": dict(
        smoothness=1.0,  # curvature in the holes, as at ci
        smoothness_edge=300.0,  # with the image in the input, act only where colour is flat
        flatness=0.6,  # first order in the holes: levels off at the border
        net_input="meshgrid",  # the pixel coordinates instead of noise, DIP's input for large holes
        noise_channels=2,  # ... x and y only
        image_input=1.0,  # the colour image in the net's input puts depth edges at colour edges
        image_blur=1.0,  # ... blurred by 1 px
        bf16=None,  # the net in bfloat16 where the CPU has it natively: faster, no worse
        blend_fill=0.25,  # a quarter of the input's fill (colorization and bilateral solver, averaged) in the
                          # result (variants with colour): better on real photographs
    ),
    "paper": {},  # at the paper's size, the paper's method
}

# on real scenes the kit's hole terms, chosen on rendered ones, hold the fit flatter than the scenes are: photo's
# answer is better without them, though a border hole may now run away (the study: docs/studies/real_suite.md)
PHOTO_HOLE_TERMS = dict(smoothness=0.0, flatness=0.0)

RECIPES = {
    "kit": Recipe("kit", {}, "the paper's losses plus what the kit found to fill large holes better at small sizes "
                             "(KIT_AT: what each profile adds, and why; at the paper's size nothing)", at=KIT_AT,
                  purpose="the default: the kit's additions for small sizes"),
    # the kit's settings at the profile with every addition switched off: what stays acts on nothing
    # (the colour-edge strength, the blur of an image that is not in the input) but bf16 at class, the
    # precision the net runs in, not what it optimises
    "paper": Recipe("paper", dict(smoothness=0.0, flatness=0.0, image_input=0.0, fill_input=0.0, net_input="noise",
                                  noise_channels=16, blend_paper=False, blend_fill=0.0),
                    "the paper's losses (Eq. 2-5) from its 16-channel noise input, nothing added", base="kit",
                    purpose="the paper's method alone"),
    # for real photographs: a fit blurs depth edges over a few pixels and a colour-guided solve puts them on
    # the photo's edges; chosen on half the real suite's scenes among fill shares and solves, confirmed on the
    # other half (docs/studies/real_suite.md)
    "photo": Recipe("photo", dict(refine=True),
                    "for real photographs: the kit's fit without its hole terms, made sharp by an image-guided "
                    "bilateral solve, with the kit's share of a colour-guided fill; one fit", base="kit",
                    at={name: PHOTO_HOLE_TERMS for name in ("ci", "class")}, purpose="for real photographs"),
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
    """What ``settings`` (``FitConfig`` fields by name, as :meth:`Recipe.settings` gives) add to the paper's
    method, for one line of a notebook's first cell: "" for the paper's method. Each kit section describes
    itself (its ``describe()``), the fields ``settings`` leaves out at their defaults."""
    return (HoleConfig.from_flat(settings).describe()
            + NetInputConfig.from_flat(settings).describe(PaperConfig.from_flat(settings).noise_channels)
            + WarpConfig.from_flat(settings).describe() + CombinationConfig.from_flat(settings).describe())
