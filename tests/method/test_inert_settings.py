"""Settings that act on nothing are said before the fit (``ddp_lite.method.inert_settings``, the recipe a
variant cuts short, the run options given where a fit's arguments go, ``complete``'s flags); the stock
recipes at every profile and variant warn about nothing; what a fit computes is left as it was."""
from __future__ import annotations

import os
import warnings

import numpy as np
import pytest

os.environ.setdefault("DDP_PROFILE", "ci")

from ddp_lite.core.camera import Camera  # noqa: E402
from ddp_lite.method.complete import complete_depth  # noqa: E402
from ddp_lite.method.config import FitConfig  # noqa: E402
from ddp_lite.method.inert_settings import InertSettingWarning, inert_settings  # noqa: E402
from ddp_lite.method.kit.recipes import RECIPES  # noqa: E402
from ddp_lite.method.paper.variants import VARIANTS  # noqa: E402
from ddp_lite.method.profiles import PROFILES  # noqa: E402
from ddp_lite.method.runtime.options import RunOptions  # noqa: E402

QUIET = RunOptions(progress=False)
TINY = dict(channels=(8, 16), iterations=2, auto_stop=False, lr_milestones=())


def _inputs(H=24, W=32):
    """A slanted plane with a square hole, a colour ramp, a camera and one neighbour one baseline right."""
    v, u = np.mgrid[0:H, 0:W]
    depth = (2.0 + 0.01 * u).astype(np.float32)
    depth[8:16, 10:20] = np.nan
    rgb = np.stack([u / W, v / H, 0.5 + 0 * u], axis=-1).astype(np.float32)
    K = np.array([[30.0, 0, W / 2], [0, 30.0, H / 2], [0, 0, 1]])
    camera = Camera(K, np.eye(4), W, H)
    moved = np.eye(4)
    moved[0, 3] = -0.1
    return rgb, depth, camera, [(rgb, Camera(K, moved, W, H))]


def _variant_names():
    return [v if isinstance(v, str) else v.name for v in VARIANTS]


@pytest.mark.parametrize("profile", sorted(PROFILES))
def test_no_stock_recipe_warns_at_any_profile_or_variant(profile):
    for recipe in RECIPES:
        for variant in _variant_names():
            with warnings.catch_warnings():
                warnings.simplefilter("error", InertSettingWarning)
                if recipe == "photo" and variant == "d":
                    with pytest.warns(InertSettingWarning):  # said by for_profile, which drops the solve
                        config = FitConfig.for_profile(profile, variant=variant, recipe=recipe)
                else:
                    config = FitConfig.for_profile(profile, variant=variant, recipe=recipe)
            neighbors = 2 if variant == "rgbd+warp" else 0
            assert inert_settings(config, variant, neighbors) == [], (profile, recipe, variant)


@pytest.mark.parametrize("change, variant, neighbors, named", [
    (dict(warp_combine="min"), "rgbd", 0, "warp_combine"),
    (dict(warp_cost="census"), "d", 0, "warp_cost"),
    (dict(warp_reach=2.0), "rgbd", 0, "warp_reach"),
    (dict(warp_combine="min"), "rgbd+warp", 1, "one neighbour"),
    (dict(gammas=(0.9, 0.05)), "d", 0, "gammas"),
    (dict(blend_weight=0.3), "rgbd", 0, "blend_weight"),
    (dict(depth_source="stereo", blend_fill=0.0, refine=False), "rgbd", 0, "depth_source"),
    (dict(edge_guide="rgb", smoothness=0.0, flatness=0.0), "rgbd", 0, "edge_guide"),
    (dict(flatness_reach=3.0, flatness=0.0), "rgbd", 0, "flatness_reach"),
])
def test_each_setting_that_acts_on_nothing_is_named(change, variant, neighbors, named):
    config = FitConfig.for_profile("ci", variant=variant, recipe="paper", **change)
    said = inert_settings(config, variant, neighbors)
    assert len(said) == 1 and named in said[0] and "acts on nothing" in said[0]


@pytest.mark.parametrize("change, variant, neighbors", [
    (dict(warp_combine="min"), "rgbd+warp", 2),  # picks between two
    (dict(depth_source="stereo", blend_fill=0.25), "rgbd", 0),  # the fill's share reads it
    (dict(depth_source="stereo", blend_fill=None), "rgbd", 0),  # a share chosen on held-out blobs reads it
    (dict(depth_source="stereo", blend_fill=0.0, refine=True), "rgbd", 0),  # the solve reads it
    (dict(blend_weight=0.3, blend_paper=True), "rgbd", 0),
    (dict(edge_guide="rgb", smoothness=1.0), "rgbd", 0),
    (dict(flatness_reach=3.0, flatness=0.6), "rgbd", 0),
    (dict(gammas=(0.9, 0.05)), "rgbd", 0),
])
def test_a_setting_that_acts_is_not_named(change, variant, neighbors):
    config = FitConfig.for_profile("ci", variant=variant, recipe="paper", **change)
    assert inert_settings(config, variant, neighbors) == []


def test_complete_depth_warns_before_the_fit_and_computes_what_it_did():
    rgb, depth, camera, neighbors = _inputs()
    config = FitConfig.for_profile("ci", variant="rgbd", recipe="paper", **TINY)
    with warnings.catch_warnings():
        warnings.simplefilter("error", InertSettingWarning)
        plain = complete_depth(rgb, depth, variant="rgbd", config=config, options=QUIET)
    with pytest.warns(InertSettingWarning, match="warp_combine='min' acts on nothing: variant 'rgbd'"):
        inert = complete_depth(rgb, depth, variant="rgbd", config=config.replace(warp_combine="min"), options=QUIET)
    np.testing.assert_array_equal(plain.depth, inert.depth)  # said, and nothing changed
    warp = FitConfig.for_profile("ci", variant="rgbd+warp", recipe="paper", warp_combine="min", **TINY)
    with pytest.warns(InertSettingWarning, match="one neighbour"):
        complete_depth(rgb, depth, camera, neighbors, variant="rgbd+warp", config=warp, options=QUIET)


def test_the_photo_recipe_for_a_depth_only_fit_says_its_solve_is_dropped():
    with pytest.warns(InertSettingWarning, match=r"recipe 'photo'.*refine.*variant 'd'"):
        config = FitConfig.for_profile("ci", variant="d", recipe="photo")
    assert config.combination.refine is False  # dropped as before: the numbers of a d fit do not change
    with warnings.catch_warnings():
        warnings.simplefilter("error", InertSettingWarning)
        assert FitConfig.for_profile("ci", variant="rgbd", recipe="photo").combination.refine is True


def test_a_callback_rate_without_a_callback_is_said():
    from ddp_lite.method.fit import check_run
    with pytest.warns(InertSettingWarning, match="callback_every=5 acts on nothing: no callback"):
        check_run(RunOptions(progress=False, callback_every=5))
    with warnings.catch_warnings():
        warnings.simplefilter("error", InertSettingWarning)
        check_run(RunOptions(progress=False, callback_every=5), callback=lambda it, out: None)
        check_run(RunOptions(progress=False))


@pytest.mark.parametrize("name", ["device", "progress", "channels_last", "max_memory_gb", "callback_every"])
def test_a_run_option_given_to_complete_depth_names_run_options(name):
    rgb, depth, _, _ = _inputs()
    with pytest.raises(TypeError, match=rf"complete_depth\(\) got {name!r}.*options=RunOptions\({name}="):
        complete_depth(rgb, depth, variant="rgbd", **{name: False})


def test_a_config_field_given_to_complete_depth_names_fitconfig():
    rgb, depth, _, _ = _inputs()
    with pytest.raises(TypeError, match=r"complete_depth\(\) got 'lr'.*config=FitConfig"):
        complete_depth(rgb, depth, variant="rgbd", lr=1e-2)
    with pytest.raises(TypeError, match=r"complete_depth\(\) got an unexpected keyword argument 'confg'.*'config'"):
        complete_depth(rgb, depth, variant="rgbd", confg=None)


@pytest.mark.parametrize("old, new", [("holdout", "held_out_shape"), ("holdout_fraction", "held_out_fraction")])
def test_an_old_spelling_of_a_field_is_refused_with_its_new_name(old, new):
    rgb, depth, _, _ = _inputs()
    value = "blobs" if new == "held_out_shape" else 0.1
    for call in (lambda: FitConfig(**{old: value}), lambda: FitConfig.for_profile("ci", **{old: value}),
                 lambda: FitConfig().replace(**{old: value}), lambda: getattr(FitConfig(), old)):
        with pytest.raises((TypeError, AttributeError), match=rf"{old!r}: the field is now {new!r}"):
            call()
    with pytest.raises(TypeError, match=rf"complete_depth\(\) got {old!r}: it is now the FitConfig field {new!r}"):
        complete_depth(rgb, depth, variant="rgbd", **{old: value})
    assert getattr(FitConfig(**{new: value}).stopping, new) == value  # the new name is the field


def test_the_other_fit_entry_points_name_run_options_too():
    from ddp_lite.method.coarse_to_fine import complete_depth_coarse_to_fine
    from ddp_lite.method.dip import fit_image
    from ddp_lite.method.fit import fit_once
    rgb, depth, _, _ = _inputs()
    for call in (lambda: complete_depth_coarse_to_fine(rgb, depth, variant="rgbd", device="cpu"),
                 lambda: fit_image(rgb, progress=False),
                 lambda: fit_once(rgb, depth, None, (), "rgbd", None, device="cpu")):
        with pytest.raises(TypeError, match=r"options=RunOptions\("):
            call()


# ------------------------------------------------------------------ ddp-lite complete's flags

def _complete(tmp_path, *flags):
    from conftest import rgbd_files as _pair
    from ddp_lite.interface.cli import main
    _pair(tmp_path)
    return main(["complete", "--rgb", str(tmp_path / "rgb.png"), "--depth", str(tmp_path / "depth.npy"),
                 "--out", str(tmp_path / "filled.npy"), "--profile", "ci", "--iterations", "2", *flags])


def _flags_said(*flags, full_shape=(60, 90)):
    """What ``complete`` says of its flags for an image of ``full_shape``, from its own parser and rules."""
    from ddp_lite.interface.cli import build_parser
    from ddp_lite.interface.cli_complete import _inert_flags
    from ddp_lite.method.kit.recipes import get_recipe
    from ddp_lite.sequences.working_size import working_shape
    args = build_parser().parse_args(["complete", "--rgb", "r.png", "--depth", "d.npy", "--out", "o.npy",
                                      "--profile", "ci", *flags])
    # as complete sets them without --scene: only a typed --depth-source is judged
    args.depth_source_given = args.depth_source is not None
    args.variant, args.depth_source = args.variant or "rgbd", args.depth_source or "clean"
    max_side = args.max_side or 64
    shape = working_shape(full_shape, max_side)
    refine = not (args.raw or args.no_refine) and shape != full_shape
    config = FitConfig.for_profile("ci", variant=args.variant, recipe=get_recipe(args.recipe),
                                   **({"blend_fill": 0.0} if args.raw else {}))
    if refine or args.raw:
        config = config.replace(refine=False)
    return _inert_flags(args, config, max_side, shape, full_shape, refine)


@pytest.mark.parametrize("flags, said", [
    (("--max-side", "16", "--raw", "--depth-source", "stereo"), "--depth-source stereo acts on nothing"),
    (("--max-side", "16", "--variant", "d", "--no-refine", "--depth-source", "stereo"),
     "--depth-source stereo acts on nothing"),
    (("--max-side", "16", "--raw", "--no-refine"), "--no-refine acts on nothing: --raw"),
    (("--max-side", "90", "--no-refine"), "--no-refine acts on nothing: the fit runs at the image's own size"),
    (("--max-side", "400"), "--max-side 400 acts on nothing"),
    (("--max-side", "90", "--recipe", "paper", "--depth-source", "stereo"), "--depth-source stereo acts on nothing"),
])
def test_complete_says_which_flag_acts_on_nothing(flags, said):
    lines = _flags_said(*flags)
    assert len(lines) == 1 and lines[0].startswith(said), lines


@pytest.mark.parametrize("flags", [
    ("--max-side", "16", "--depth-source", "stereo"),  # the fill's share and the full-size solve read it
    ("--max-side", "16", "--recipe", "paper", "--depth-source", "stereo"),  # the full-size solve reads it
    ("--max-side", "90", "--recipe", "photo", "--depth-source", "stereo"),  # photo's own solve reads it
    ("--max-side", "16", "--no-refine"),
    ("--max-side", "16", "--raw"),
    ("--max-side", "90"),
])
def test_complete_is_silent_where_each_flag_acts(flags):
    assert _flags_said(*flags) == []


def test_complete_says_it_before_the_fit_and_the_fit_is_told_nothing_inert(tmp_path, capsys):
    assert _complete(tmp_path, "--max-side", "16", "--raw", "--depth-source", "stereo") == 0
    err = capsys.readouterr().err
    assert err.count("acts on nothing") == 1  # the flag, said once; not again by the fit as its config field
    assert "ddp-lite complete: warning: --depth-source stereo acts on nothing" in err
