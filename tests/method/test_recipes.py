"""Recipes are orthogonal to profiles: the paper's method at every size, the kit's additions by name."""
import numpy as np
import pytest

from ddp_lite.classical.holes import random_holes
from ddp_lite.method.complete import complete_depth
from ddp_lite.world.scenes import make_scene
from ddp_lite.method.config import FitConfig
from ddp_lite.method.profiles import PROFILES
from ddp_lite.method.kit.recipes import RECIPES, get_recipe


@pytest.mark.parametrize("profile", sorted(PROFILES))
def test_the_paper_recipe_adds_nothing_at_any_size(profile):
    config = FitConfig.for_profile(profile, variant="rgbd", recipe="paper")
    assert (config.holes.smoothness, config.holes.flatness) == (0.0, 0.0)
    assert (config.net_inputs.image_input, config.net_inputs.fill_input) == (0.0, 0.0)
    assert config.net_inputs.base == "noise" and config.paper.noise_channels == 16  # the paper's 16 noise channels
    size_and_budget = ("channels", "iterations", "lr", "lr_milestones", "auto_stop", "patience")
    kit = FitConfig.for_profile(profile, variant="rgbd", recipe="kit")
    assert all(config.flat()[name] == kit.flat()[name] for name in size_and_budget)  # the profile decides these


def test_the_paper_recipe_optimises_only_the_papers_three_terms():
    scene = make_scene("desk", size=(24, 32), n_views=2, seed=0)
    depth, _ = random_holes(scene[0].depth, seed=0)
    nbrs = [scene[1].as_neighbor()]
    terms = {}
    for recipe in ("paper", "kit"):
        config = FitConfig.for_profile("ci", variant="rgbd+warp", recipe=recipe, iterations=3,
                                       channels=(8, 16))
        result = complete_depth(scene[0].rgb, depth, scene[0].camera, nbrs, variant="rgbd+warp", config=config)
        terms[recipe] = {k for k in result.history if k in ("disp", "rgb", "warp", "smooth", "flat")}
    assert terms["paper"] == {"disp", "rgb", "warp"}
    assert {"smooth", "flat"} <= terms["kit"]


def test_ddp_recipe_selects_the_default_and_bad_names_are_refused(monkeypatch):
    monkeypatch.setenv("DDP_RECIPE", "paper")
    assert FitConfig.for_profile("class", variant="rgbd").holes.smoothness == 0.0
    monkeypatch.setenv("DDP_RECIPE", "kit")
    assert FitConfig.for_profile("class", variant="rgbd").holes.smoothness == RECIPES["kit"].at["class"]["smoothness"] > 0
    monkeypatch.setenv("DDP_RECIPE", "papr")
    with pytest.raises(ValueError, match="DDP_RECIPE must be one of"):
        FitConfig.for_profile("class", variant="rgbd")
    with pytest.raises(ValueError, match="recipe must be one of"):
        get_recipe("bogus")
    assert set(RECIPES) >= {"paper", "kit"}


@pytest.mark.parametrize("profile", ["ci", "class", "paper"])
@pytest.mark.parametrize("recipe", ["paper", "kit", "photo"])
def test_a_recipes_line_says_what_that_recipe_runs_at_the_profile(profile, recipe):
    """The recipe line a notebook prints names each addition the config it builds has switched on, and none it
    has off (notebook 09 runs photo: its lines must not name the kit's hole terms); the profile line above it
    names size and budget only, so the two cannot disagree."""
    from ddp_lite.method.config import FitConfig
    from ddp_lite.method.profiles import get_profile
    config = FitConfig.for_profile(profile, variant="rgbd", recipe=recipe).flat()
    first, line = get_profile(profile).describe(recipe).split("\n")
    assert line == get_recipe(recipe).describe(profile) and line.startswith(f"recipe '{recipe}'")
    switched = {"hole curvature": config["smoothness"] > 0, "hole flatness": config["flatness"] > 0,
                "the colour image": config["image_input"] > 0, "pixel coordinates": config["net_input"] == "meshgrid",
                "made sharp": config["refine"], "colour-guided fill": config["blend_fill"] > 0}
    assert {words: words in line for words in switched} == switched, line
    assert ("nothing added" in line) == (not any(switched.values()))
    assert not any(words in first for words in switched) and "recipe" not in first
    assert first == get_profile(profile).describe()


def test_the_loss_equation_marks_exactly_the_kits_additions():
    from ddp_lite.method.config import FitConfig
    from ddp_lite.method.equation import loss_equation
    paper = loss_equation(FitConfig.for_profile("class", variant="rgbd+warp", recipe="paper"), "rgbd+warp")
    assert paper == ("\\min_\\theta\\ 0.96\\,L^{\\mathrm{disp}} + 0.02\\,L^{\\mathrm{RGB}} + 0.02\\,L^{\\mathrm{warp}},"
                     "\\quad (Z, I) = f_\\theta(\\text{noise})")  # Eq. 5 with the supplement's γ, by hand
    kit = loss_equation(FitConfig.for_profile("class", variant="rgbd", recipe="kit"), "rgbd")
    assert kit.count("not in the paper") == 3  # the hole terms, the input, and the fill's share in the result
    assert "1\\,L^{\\mathrm{curv}}_{w} + 0.6\\,L^{\\mathrm{flat}}_{w}" in kit and "u, v, G_{1} * I" in kit
    assert "\\hat Z = 0.75\\,Z + 0.25\\,\\mathrm{fill}(Z_{\\mathrm{in}})" in kit
    depth_only = loss_equation(FitConfig.for_profile("class", variant="d", recipe="kit"), "d")
    assert "G_" not in depth_only and "L^{\\mathrm{RGB}}" not in depth_only  # no image for depth-only
    assert "fill" not in depth_only  # nor a colour-guided fill in its result


def test_a_colour_guided_fill_never_enters_a_depth_only_result():
    from ddp_lite.method.config import FitConfig
    assert FitConfig.for_profile("class", variant="rgbd", recipe="kit").combination.blend_fill == 0.25
    assert FitConfig.for_profile("class", variant="d", recipe="kit").combination.blend_fill == 0.0
    with pytest.warns(UserWarning, match="dropped for variant 'd'"):  # said: photo's solve is its point
        assert FitConfig.for_profile("class", variant="d", recipe="photo").combination.blend_fill == 0.0
    assert FitConfig.for_profile("ci", variant="rgbd", recipe="kit").combination.blend_fill == 0.25  # as at class
    assert FitConfig.for_profile("ci", variant="d", recipe="kit").combination.blend_fill == 0.0


@pytest.mark.parametrize("profile", ["ci", "class", "paper"])
def test_the_additions_path_runs_from_the_paper_recipe_to_the_kit(profile):
    from ddp_lite.studies.additions import addition_steps
    from ddp_lite.method.config import FitConfig
    steps = addition_steps(profile)
    configs = [FitConfig.for_profile(profile, variant="rgbd", recipe="paper", **o) for o in steps.values()]
    assert configs[0] == FitConfig.for_profile(profile, variant="rgbd", recipe="paper")
    assert configs[-1] == FitConfig.for_profile(profile, variant="rgbd", recipe="kit")
    assert len(set(map(repr, configs))) == len(configs)  # every step changes something


def test_the_additions_path_fits_at_its_cases_profile_net_with_the_profiles_budget(monkeypatch):
    """Notebook 10 at `class` fits its cases at `ci`'s size with `ci`'s net (``net_of``) and `class`'s recipe
    and budget: every fit's config says so, field by field, against the profiles' own tables."""
    from ddp_lite.method.profiles import PROFILES
    from ddp_lite.studies import additions

    seen = []

    class Recorded(Exception):
        pass

    def record(*args, config, **kwargs):
        seen.append(config.flat())
        raise Recorded
    monkeypatch.setattr(additions, "complete_depth", record)
    cases = additions.additions_cases("ci", ("house",), ())
    for net_of, widths in ((None, PROFILES["class"].channels), ("ci", PROFILES["ci"].channels)):
        seen.clear()
        with pytest.raises(Recorded):
            additions.run_additions(cases, "class", seeds=(0,), log=lambda *_: None, net_of=net_of)
        assert seen and all(c["channels"] == widths for c in seen), (net_of, seen)
        assert all(c["auto_stop"] is True and c["iterations"] == PROFILES["class"].iterations for c in seen)
