"""Recipes are orthogonal to profiles: the paper's method at every size, the kit's additions by name."""
import numpy as np
import pytest

import ddp_lite as ddp
from ddp_lite.method.config import FitConfig
from ddp_lite.method.profiles import PROFILES
from ddp_lite.method.recipes import RECIPES, get_recipe


@pytest.mark.parametrize("profile", sorted(PROFILES))
def test_the_paper_recipe_adds_nothing_at_any_size(profile):
    config = FitConfig.for_profile(profile, variant="rgbd", recipe="paper")
    assert (config.smoothness, config.flatness, config.image_input, config.fill_input) == (0.0, 0.0, 0.0, 0.0)
    assert config.net_input == "noise" and config.noise_channels == 16  # the paper's 16 noise channels
    size_and_budget = ("channels", "iterations", "lr", "lr_milestones", "auto_stop", "patience")
    kit = FitConfig.for_profile(profile, variant="rgbd", recipe="kit")
    assert all(getattr(config, name) == getattr(kit, name) for name in size_and_budget)  # the profile decides these


def test_the_paper_recipe_optimises_only_the_papers_three_terms():
    scene = ddp.make_scene("desk", size=(24, 32), n_views=2, seed=0)
    depth, _ = ddp.random_holes(scene[0].depth, seed=0)
    nbrs = [scene[1].as_neighbor()]
    terms = {}
    for recipe in ("paper", "kit"):
        config = FitConfig.for_profile("ci", variant="rgbd+warp", recipe=recipe, iterations=3, progress=False,
                                       channels=(8, 16))
        result = ddp.complete_depth(scene[0].rgb, depth, scene[0].camera, nbrs, variant="rgbd+warp", config=config)
        terms[recipe] = {k for k in result.history if k in ("disp", "rgb", "warp", "smooth", "flat")}
    assert terms["paper"] == {"disp", "rgb", "warp"}
    assert {"smooth", "flat"} <= terms["kit"]


def test_ddp_recipe_selects_the_default_and_bad_names_are_refused(monkeypatch):
    monkeypatch.setenv("DDP_RECIPE", "paper")
    assert FitConfig.for_profile("class", variant="rgbd").smoothness == 0.0
    monkeypatch.setenv("DDP_RECIPE", "kit")
    assert FitConfig.for_profile("class", variant="rgbd").smoothness == RECIPES["kit"].at["class"]["smoothness"] > 0
    monkeypatch.setenv("DDP_RECIPE", "papr")
    with pytest.raises(ValueError, match="DDP_RECIPE must be one of"):
        FitConfig.for_profile("class", variant="rgbd")
    with pytest.raises(ValueError, match="recipe must be one of"):
        get_recipe("bogus")
    assert set(RECIPES) >= {"paper", "kit"}


def test_a_profiles_first_line_names_what_the_recipe_in_force_adds():
    from ddp_lite.method.profiles import get_profile
    profile = get_profile("class")
    assert "curvature" in profile.describe("kit") and "coordinates" in profile.describe("kit")
    paper = profile.describe("paper")
    assert "curvature" not in paper and "flatness" not in paper and "input:" not in paper
    assert paper == profile.describe("kit").split(", hole curvature")[0]  # the size and budget are the same
