"""Profiles and recipes build exactly the configs they built when a profile still carried the
method: every (profile, recipe, variant, net) pinned field by field, and the notebooks' first line."""

import pytest

from ddp_lite.method.config import FitConfig
from ddp_lite.method.profiles import PROFILES

DEFAULTS = dict(
    # paper
    net='unet', channels=None, down='stride', up='bilinear', pad='reflect', noise_channels=16, lr=5e-05,
    schedule='step', iterations=None, lr_milestones=(12000, 15000), lr_gamma=0.01, lambda_z=0.8, lambda_i=0.5,
    lambda_w=0.5, gammas=None, disparity_margin=1.25, seed=0,
    # net_inputs
    net_input='noise', image_input=0.0, image_blur=1.0, fill_input=0.0, fill_start=False,
    # holes
    smoothness=0.0, smoothness_edge=10.0, edge_guide='grey', flatness=0.0, affinity=0.0, flatness_reach=None,
    step_reach=None,
    # warp
    warp_occlusion=False, warp_confidence=False, warp_reach=None, warp_cost='intensity', warp_texture=False,
    warp_combine='mean',
    # combination
    ensemble=1, blend_paper=False, blend_weight=0.5, blend_fill=0.0, refine=False, depth_source='clean',
    # stopping
    auto_stop=False, held_out_fraction=0.05, held_out_shape='pixels', patience=200, plateau_decays=0, eval_every=10,
    # tricks
    reg_noise_std=0.0, average_outputs=0.0,
    # precision
    bf16=False)

# (profile, recipe, variant, net) → the fields that differ from DEFAULTS
EXPECTED = {
    ('ci', 'kit', 'd', 'unet'): dict(
        channels=(8, 16, 32, 64), image_input=1.0, image_blur=0.5, lr=0.01, iterations=150, lr_milestones=(90,
        128), lr_gamma=0.3, smoothness=1.0, smoothness_edge=100.0, flatness=0.6, patience=60),
    ('ci', 'kit', 'd', 'skip'): dict(
        net='skip', channels=(32, 32, 32, 32), image_input=1.0, image_blur=0.5, lr=0.01, iterations=150,
        lr_milestones=(90, 128), lr_gamma=0.3, smoothness=1.0, smoothness_edge=100.0, flatness=0.6, patience=60),
    ('ci', 'kit', 'rgbd', 'unet'): dict(
        channels=(8, 16, 32, 64), image_input=1.0, image_blur=0.5, lr=0.01, iterations=150, lr_milestones=(90,
        128), lr_gamma=0.3, smoothness=1.0, smoothness_edge=100.0, flatness=0.6, patience=60, blend_fill=0.25),
    ('ci', 'kit', 'rgbd', 'skip'): dict(
        net='skip', channels=(32, 32, 32, 32), image_input=1.0, image_blur=0.5, lr=0.01, iterations=150,
        lr_milestones=(90, 128), lr_gamma=0.3, smoothness=1.0, smoothness_edge=100.0, flatness=0.6, patience=60, blend_fill=0.25),
    ('ci', 'kit', 'rgbd+warp', 'unet'): dict(
        channels=(8, 16, 32, 64), image_input=1.0, image_blur=0.5, lr=0.01, iterations=150, lr_milestones=(90,
        128), lr_gamma=0.3, smoothness=1.0, smoothness_edge=100.0, flatness=0.6, patience=60, blend_fill=0.25),
    ('ci', 'kit', 'rgbd+warp', 'skip'): dict(
        net='skip', channels=(32, 32, 32, 32), image_input=1.0, image_blur=0.5, lr=0.01, iterations=150,
        lr_milestones=(90, 128), lr_gamma=0.3, smoothness=1.0, smoothness_edge=100.0, flatness=0.6, patience=60, blend_fill=0.25),
    ('ci', 'paper', 'd', 'unet'): dict(
        channels=(8, 16, 32, 64), image_blur=0.5, lr=0.01, iterations=150, lr_milestones=(90, 128),
        lr_gamma=0.3, smoothness_edge=100.0, patience=60),
    ('ci', 'paper', 'd', 'skip'): dict(
        net='skip', channels=(32, 32, 32, 32), image_blur=0.5, lr=0.01, iterations=150, lr_milestones=(90, 128),
        lr_gamma=0.3, smoothness_edge=100.0, patience=60),
    ('ci', 'paper', 'rgbd', 'unet'): dict(
        channels=(8, 16, 32, 64), image_blur=0.5, lr=0.01, iterations=150, lr_milestones=(90, 128),
        lr_gamma=0.3, smoothness_edge=100.0, patience=60),
    ('ci', 'paper', 'rgbd', 'skip'): dict(
        net='skip', channels=(32, 32, 32, 32), image_blur=0.5, lr=0.01, iterations=150, lr_milestones=(90, 128),
        lr_gamma=0.3, smoothness_edge=100.0, patience=60),
    ('ci', 'paper', 'rgbd+warp', 'unet'): dict(
        channels=(8, 16, 32, 64), image_blur=0.5, lr=0.01, iterations=150, lr_milestones=(90, 128),
        lr_gamma=0.3, smoothness_edge=100.0, patience=60),
    ('ci', 'paper', 'rgbd+warp', 'skip'): dict(
        net='skip', channels=(32, 32, 32, 32), image_blur=0.5, lr=0.01, iterations=150, lr_milestones=(90, 128),
        lr_gamma=0.3, smoothness_edge=100.0, patience=60),
    ('class', 'kit', 'd', 'unet'): dict(
        channels=(16, 32, 64, 128, 256), noise_channels=2, net_input='meshgrid', image_input=1.0, lr=0.01,
        iterations=600, lr_milestones=(), lr_gamma=0.3, smoothness=1.0, smoothness_edge=300.0, flatness=0.6,
        auto_stop=True, patience=50, plateau_decays=1, bf16=None),
    ('class', 'kit', 'd', 'skip'): dict(
        net='skip', channels=(128, 128, 128, 128, 128), noise_channels=2, net_input='meshgrid', image_input=1.0,
        lr=0.01, iterations=600, lr_milestones=(), lr_gamma=0.3, smoothness=1.0, smoothness_edge=300.0,
        flatness=0.6, auto_stop=True, patience=50, plateau_decays=1, bf16=None),
    ('class', 'kit', 'rgbd', 'unet'): dict(
        channels=(16, 32, 64, 128, 256), noise_channels=2, net_input='meshgrid', image_input=1.0, lr=0.01,
        iterations=600, lr_milestones=(), lr_gamma=0.3, smoothness=1.0, smoothness_edge=300.0, flatness=0.6,
        auto_stop=True, patience=50, plateau_decays=1, bf16=None, blend_fill=0.25),
    ('class', 'kit', 'rgbd', 'skip'): dict(
        net='skip', channels=(128, 128, 128, 128, 128), noise_channels=2, net_input='meshgrid', image_input=1.0,
        lr=0.01, iterations=600, lr_milestones=(), lr_gamma=0.3, smoothness=1.0, smoothness_edge=300.0,
        flatness=0.6, auto_stop=True, patience=50, plateau_decays=1, bf16=None, blend_fill=0.25),
    ('class', 'kit', 'rgbd+warp', 'unet'): dict(
        channels=(16, 32, 64, 128, 256), noise_channels=2, net_input='meshgrid', image_input=1.0, lr=0.01,
        iterations=600, lr_milestones=(), lr_gamma=0.3, smoothness=1.0, smoothness_edge=300.0, flatness=0.6,
        auto_stop=True, patience=50, plateau_decays=1, bf16=None, blend_fill=0.25),
    ('class', 'kit', 'rgbd+warp', 'skip'): dict(
        net='skip', channels=(128, 128, 128, 128, 128), noise_channels=2, net_input='meshgrid', image_input=1.0,
        lr=0.01, iterations=600, lr_milestones=(), lr_gamma=0.3, smoothness=1.0, smoothness_edge=300.0,
        flatness=0.6, auto_stop=True, patience=50, plateau_decays=1, bf16=None, blend_fill=0.25),
    ('class', 'paper', 'd', 'unet'): dict(
        channels=(16, 32, 64, 128, 256), lr=0.01, iterations=600, lr_milestones=(), lr_gamma=0.3,
        smoothness_edge=300.0, auto_stop=True, patience=50, plateau_decays=1, bf16=None),
    ('class', 'paper', 'd', 'skip'): dict(
        net='skip', channels=(128, 128, 128, 128, 128), lr=0.01, iterations=600, lr_milestones=(), lr_gamma=0.3,
        smoothness_edge=300.0, auto_stop=True, patience=50, plateau_decays=1, bf16=None),
    ('class', 'paper', 'rgbd', 'unet'): dict(
        channels=(16, 32, 64, 128, 256), lr=0.01, iterations=600, lr_milestones=(), lr_gamma=0.3,
        smoothness_edge=300.0, auto_stop=True, patience=50, plateau_decays=1, bf16=None),
    ('class', 'paper', 'rgbd', 'skip'): dict(
        net='skip', channels=(128, 128, 128, 128, 128), lr=0.01, iterations=600, lr_milestones=(), lr_gamma=0.3,
        smoothness_edge=300.0, auto_stop=True, patience=50, plateau_decays=1, bf16=None),
    ('class', 'paper', 'rgbd+warp', 'unet'): dict(
        channels=(16, 32, 64, 128, 256), lr=0.01, iterations=600, lr_milestones=(), lr_gamma=0.3,
        smoothness_edge=300.0, auto_stop=True, patience=50, plateau_decays=1, bf16=None),
    ('class', 'paper', 'rgbd+warp', 'skip'): dict(
        net='skip', channels=(128, 128, 128, 128, 128), lr=0.01, iterations=600, lr_milestones=(), lr_gamma=0.3,
        smoothness_edge=300.0, auto_stop=True, patience=50, plateau_decays=1, bf16=None),
    ('paper', 'kit', 'd', 'unet'): dict(
        channels=(32, 64, 128, 256, 512), iterations=6000, lr_milestones=(), patience=2000, eval_every=100),
    ('paper', 'kit', 'd', 'skip'): dict(
        net='skip', channels=(128, 128, 128, 128, 128), iterations=6000, lr_milestones=(), patience=2000,
        eval_every=100),
    ('paper', 'kit', 'rgbd', 'unet'): dict(
        channels=(32, 64, 128, 256, 512), iterations=16000, patience=2000, eval_every=100),
    ('paper', 'kit', 'rgbd', 'skip'): dict(
        net='skip', channels=(128, 128, 128, 128, 128), iterations=16000, patience=2000, eval_every=100),
    ('paper', 'kit', 'rgbd+warp', 'unet'): dict(
        channels=(32, 64, 128, 256, 512), iterations=16000, patience=2000, eval_every=100),
    ('paper', 'kit', 'rgbd+warp', 'skip'): dict(
        net='skip', channels=(128, 128, 128, 128, 128), iterations=16000, patience=2000, eval_every=100),
    ('paper', 'paper', 'd', 'unet'): dict(
        channels=(32, 64, 128, 256, 512), iterations=6000, lr_milestones=(), patience=2000, eval_every=100),
    ('paper', 'paper', 'd', 'skip'): dict(
        net='skip', channels=(128, 128, 128, 128, 128), iterations=6000, lr_milestones=(), patience=2000,
        eval_every=100),
    ('paper', 'paper', 'rgbd', 'unet'): dict(
        channels=(32, 64, 128, 256, 512), iterations=16000, patience=2000, eval_every=100),
    ('paper', 'paper', 'rgbd', 'skip'): dict(
        net='skip', channels=(128, 128, 128, 128, 128), iterations=16000, patience=2000, eval_every=100),
    ('paper', 'paper', 'rgbd+warp', 'unet'): dict(
        channels=(32, 64, 128, 256, 512), iterations=16000, patience=2000, eval_every=100),
    ('paper', 'paper', 'rgbd+warp', 'skip'): dict(
        net='skip', channels=(128, 128, 128, 128, 128), iterations=16000, patience=2000, eval_every=100),
}

DESCRIBED = {
    "ci": "profile 'ci': 48×64 images, UNet 8-16-32-64, 150 iterations (depth-only 150), lr 0.01, auto-stop off",
    "class": "profile 'class': 96×128 images, UNet 16-32-64-128-256, ≤ 600 iterations (depth-only 600), lr 0.01, "
             "auto-stop on",
    "paper": "profile 'paper': 512×960 images, UNet 32-64-128-256-512, 16000 iterations (depth-only 6000), lr 5e-05, "
             "auto-stop off",
}


def fields(config: FitConfig) -> dict:
    return config.flat()


def test_the_defaults_are_the_papers_and_unchanged():
    assert fields(FitConfig()) == DEFAULTS


@pytest.mark.parametrize("key", sorted(EXPECTED))
def test_every_profile_recipe_variant_and_net_builds_its_pinned_config(key, monkeypatch):
    monkeypatch.delenv("DDP_PROFILE", raising=False)
    monkeypatch.delenv("DDP_RECIPE", raising=False)
    profile, recipe, variant, net = key
    config = fields(FitConfig.for_profile(profile, variant=variant, recipe=recipe, net=net))
    expected = {**DEFAULTS, **EXPECTED[key]}
    assert config == expected
    assert {name: type(value) for name, value in config.items()} == {n: type(v) for n, v in expected.items()}


@pytest.mark.parametrize("name", sorted(PROFILES))
def test_a_notebooks_first_line_is_unchanged(name):
    assert PROFILES[name].describe() == DESCRIBED[name]


@pytest.mark.parametrize("key", [("ci", "kit", "rgbd+warp", "unet"), ("class", "paper", "d", "skip")])
def test_a_config_and_its_fields_by_name_make_each_other(key):
    profile, recipe, variant, net = key
    config = FitConfig.for_profile(profile, variant=variant, recipe=recipe, net=net)
    assert FitConfig(**config.flat()) == config
    assert list(config.flat()) == list(DEFAULTS)  # one flat order, section by section


# the fields whose flat name (FitConfig's keyword, flat()'s key, the fit cache's key) is qualified by their
# section, which names them without the repeat: flat name → (section, field, a value other than the default)
QUALIFIED = {"net_input": ("net_inputs", "base", "meshgrid"), "warp_occlusion": ("warp", "occlusion", True),
             "warp_confidence": ("warp", "confidence", True), "warp_reach": ("warp", "reach", 2.0),
             "warp_cost": ("warp", "cost", "census"), "warp_texture": ("warp", "texture", True),
             "warp_combine": ("warp", "combine", "min")}


@pytest.mark.parametrize("flat", sorted(QUALIFIED))
def test_a_section_qualified_flat_name_sets_and_reads_its_field(flat):
    section, field, value = QUALIFIED[flat]
    for config in (FitConfig(**{flat: value}), FitConfig().replace(**{flat: value}),
                   FitConfig.for_profile("ci", variant="rgbd+warp", recipe="paper", **{flat: value})):
        assert getattr(getattr(config, section), field) == value
        assert config.flat()[flat] == value and field not in config.flat()
        assert FitConfig(**config.flat()) == config
    assert getattr(getattr(FitConfig(), section), field) == DEFAULTS[flat]


def test_the_flat_names_are_unique_and_qualified_where_the_section_drops_its_name():
    import dataclasses

    from ddp_lite.method.config import FIELDS, QUALIFIED_NAMES, SECTIONS
    assert len(FIELDS) == len(set(FIELDS)) == sum(len(dataclasses.fields(cls)) for cls in SECTIONS.values())
    assert QUALIFIED_NAMES == {flat: f"config.{section}.{field}" for flat, (section, field, _) in QUALIFIED.items()}


def test_a_sections_own_description_reads_its_fields_by_their_flat_names():
    from ddp_lite.method.kit.recipes import describe_method
    assert "pixel coordinates" in describe_method({"net_input": "meshgrid", "noise_channels": 2})
    assert "only where the neighbour can see" in describe_method({"warp_occlusion": True})
    assert "from the neighbour that agrees best" in describe_method({"warp_combine": "min"})


def test_a_sections_field_given_by_its_flat_name_says_both_names():
    from ddp_lite.method.kit.warp_terms import WarpConfig
    with pytest.raises(TypeError, match=r"WarpConfig has no field 'warp_cost': the field is 'cost' "
                                        r"\(config\.warp\.cost\).*FitConfig\(warp_cost="):
        WarpConfig(warp_cost="census")
    with pytest.raises(AttributeError, match=r"'warp_reach' as 'reach': config\.warp\.reach"):
        FitConfig().warp.warp_reach  # noqa: B018
    assert not hasattr(FitConfig().warp, "cosst")  # an unknown name is still just no attribute


def test_a_profile_names_each_config_field_it_sets():
    """The profile → config table is explicit: each field it names is a config field, and each value is the
    profile's own (a rename on either side fails here, not in a copy that silently stops)."""
    from ddp_lite.method.config import FIELDS
    for profile in PROFILES.values():
        settings = profile.fit_settings("rgbd", "skip")
        assert set(settings) <= set(FIELDS)
        assert (settings["lr"], settings["lr_gamma"], settings["auto_stop"], settings["patience"],
                settings["plateau_decays"], settings["eval_every"]) == (
            profile.lr, profile.lr_gamma, profile.auto_stop, profile.patience, profile.plateau_decays, profile.eval_every)
        assert settings["channels"] == profile.skip_channels and settings["net"] == "skip"


def test_checking_a_fits_inputs_reads_no_environment(monkeypatch):
    """A check is given its config; only the entry points read DDP_PROFILE / DDP_RECIPE (for config=None)."""
    import numpy as np

    from ddp_lite.method.input_checks import check_fit_inputs
    depth = np.full((32, 32), 2.0, np.float32)
    depth[8:16, 8:16] = np.nan
    config = FitConfig(channels=(8, 16), lr=1e-2, iterations=2)
    monkeypatch.setenv("DDP_PROFILE", "no-such-profile")
    monkeypatch.setenv("DDP_RECIPE", "no-such-recipe")
    inputs, checked = check_fit_inputs(None, depth, None, (), "d", config, None, None)
    assert checked is config and inputs.depth.shape == (32, 32)
    with pytest.raises(TypeError, match="config must be a FitConfig"):
        check_fit_inputs(None, depth, None, (), "d", None, None, None)
