"""Recipes: *which method* a fit runs, apart from *how big* it is (the profile).

A profile (``ci``, ``class``, ``paper``; ``DDP_PROFILE``) sets the size and the budget. A recipe
(``DDP_RECIPE``, or ``recipe=`` of :meth:`FitConfig.for_profile`) says what is optimised:

- ``paper``: the paper's method and nothing else: L_disp, L_rgb, L_warp (Eq. 1–4) with their
  weights, from the fixed noise input; no hole terms, no coordinates or image in the input.
- ``kit``: the profile's own method: at ``ci`` and ``class`` the paper's losses *plus* what the kit
  found to help at laptop sizes (the curvature and flatness terms in the holes, relaxed at colour
  edges; the pixel coordinates and the blurred colour image as the net's input: ``profiles.py``
  says which profile has which); at ``paper`` it is the paper's method.

Every profile runs with every recipe, so ``FitConfig.for_profile("ci", recipe="paper")`` is the
paper's method in seconds. ``docs/`` holds the evidence behind the kit's additions.
"""
from __future__ import annotations

from dataclasses import dataclass, field

from .checks import env_choice, named_choice

__all__ = ["Recipe", "RECIPES", "ENV_VAR", "DEFAULT", "current_recipe_name", "get_recipe"]

ENV_VAR = "DDP_RECIPE"
DEFAULT = "kit"


@dataclass(frozen=True)
class Recipe:
    """A named set of ``FitConfig`` overrides applied on top of a profile's config, and why."""

    name: str
    overrides: dict = field(default_factory=dict)
    why: str = ""


RECIPES = {
    "kit": Recipe("kit", {}, "the profile's own method: at ci and class the paper's losses plus the kit's "
                             "hole terms and net inputs, which fill large holes better at small sizes"),
    "paper": Recipe("paper", dict(smoothness=0.0, flatness=0.0, image_input=0.0, fill_input=0.0, net_input="noise",
                                  noise_channels=16),
                    "the paper's losses (Eq. 1-4) from its 16-channel noise input, nothing added"),
}


def current_recipe_name() -> str:
    """The recipe ``DDP_RECIPE`` names (default ``kit``)."""
    return env_choice(ENV_VAR, DEFAULT, RECIPES)


def get_recipe(name: str | Recipe | None = None) -> Recipe:
    """The named recipe, or the one ``DDP_RECIPE`` selects; a :class:`Recipe` is returned as is."""
    if isinstance(name, Recipe):
        return name
    return named_choice(name, RECIPES, "recipe", current_recipe_name)
