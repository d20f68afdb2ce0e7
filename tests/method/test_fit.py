"""The networks, the losses' masking, and short fits on analytic cases."""
import numpy as np
import pytest
import torch
from scipy.interpolate import griddata

from ddp_lite.core.camera import Camera, look_at
from ddp_lite.method.config import FitConfig
from ddp_lite.method.paper.nets import SkipNet, UNet
from ddp_lite.method.complete import complete_depth
from ddp_lite.method.paper.losses import disparity_loss, warp_loss
from ddp_lite.method.dip import fit_image
from ddp_lite.method.result import merge
from ddp_lite.method.runtime.options import RunOptions
from ddp_lite.method.paper.warp import warp_to_reference
from ddp_lite.method.stopping import PlateauStopper
from conftest import TINY, tilted_plane


def slanted_plane(height=32, width=48):
    """Depth of a plane tilted in x (metres) and a hole in its middle."""
    gt = tilted_plane(height, width)
    depth = gt.copy()
    depth[10:22, 18:30] = np.nan
    return gt, depth


def nearest_fill(depth):
    valid = np.isfinite(depth)
    rows, cols = np.nonzero(valid)
    grid = np.stack(np.mgrid[0:depth.shape[0], 0:depth.shape[1]], axis=-1).reshape(-1, 2)
    return griddata((rows, cols), depth[valid], grid, method="nearest").reshape(depth.shape)


@pytest.mark.parametrize("net_class", [UNet, SkipNet])
@pytest.mark.parametrize("size", [(17, 23), (48, 64), (5, 70)])
def test_nets_keep_any_image_size(net_class, size):
    net = net_class(16, 4, (8, 8, 8)) if net_class is UNet else net_class(16, 4, (8, 8), (2, 2))
    out = net(torch.rand(1, 16, *size))
    assert out.shape == (1, 4, *size) and out.min() >= 0 and out.max() <= 1


def test_depth_loss_gradient_is_exactly_zero_inside_holes():
    torch.manual_seed(0)
    target = torch.rand(1, 1, 32, 32)
    mask = torch.ones(1, 1, 32, 32, dtype=torch.bool)
    mask[..., 10:20, 12:22] = False
    target[~mask] = 123.0  # what the ground truth holds in the hole must not matter
    output = torch.rand(1, 1, 32, 32, requires_grad=True)
    disparity_loss(output, target, mask).backward()
    assert torch.all(output.grad[~mask] == 0)
    assert torch.all(output.grad[mask].abs().sum() > 0)
    # and the loss value does not see the hole's ground truth either
    other = target.clone()
    other[~mask] = -5.0
    assert disparity_loss(output, target, mask).item() == pytest.approx(disparity_loss(output, other, mask).item())


def test_warp_loss_prefers_the_true_depth():
    ref = Camera.from_fov(48, 32, 60.0)
    nbr = Camera(ref.K, look_at([0.2, 0.0, 0.0], [0.2, 0.0, 3.0]), 48, 32)
    rng = np.random.default_rng(0)
    texture = rng.random((32, 64, 3)).astype(np.float32)
    # neighbour image of a fronto-parallel textured plane at 2 m: ref pixel u ↔ nbr pixel u - f·b/Z
    shift = ref.focal * 0.2 / 2.0
    u = np.arange(48)
    cols = np.clip(u + 8, 0, 63)
    ref_img = texture[:, cols]
    nbr_cols = np.clip(np.round(u + shift + 8).astype(int), 0, 63)
    nbr_img = texture[:, nbr_cols]
    losses = []
    for depth in (2.0, 1.2):
        warped, valid = warp_to_reference(nbr_img, np.full((32, 48), depth, np.float32), ref, nbr)
        to_t = lambda a: torch.from_numpy(np.ascontiguousarray(a.transpose(2, 0, 1)))[None]
        losses.append(warp_loss(to_t(ref_img), [to_t(warped)], [torch.from_numpy(valid)[None, None]]).item())
    assert losses[0] < 0.5 * losses[1]


def test_a_short_fit_fills_a_hole_better_than_nearest_neighbour():
    gt, depth = slanted_plane()
    rgb = np.zeros((32, 48, 3), np.float32)
    result = complete_depth(rgb, depth, variant="d", gt_depth=gt, config=FitConfig(iterations=60, **TINY))
    holes = np.isnan(depth)
    rmse = lambda d: float(np.sqrt(np.mean((d[holes] - gt[holes]) ** 2)))
    initial = result.history["hole_rmse_m"][0]
    assert rmse(result.depth) < 0.5 * initial
    assert rmse(result.depth) < 0.7 * rmse(nearest_fill(depth))
    assert result.depth.shape == depth.shape and np.isfinite(result.depth).all()


def test_same_seed_same_numbers_and_inputs_untouched():
    gt, depth = slanted_plane()
    rgb = np.random.default_rng(0).random((32, 48, 3)).astype(np.float32)
    before = (depth.copy(), rgb.copy())
    config = FitConfig(iterations=12, **TINY)
    a = complete_depth(rgb, depth, variant="rgbd", config=config)
    b = complete_depth(rgb, depth, variant="rgbd", config=config)
    np.testing.assert_array_equal(a.depth, b.depth)
    np.testing.assert_array_equal(a.history["loss"], b.history["loss"])
    c = complete_depth(rgb, depth, variant="rgbd", config=config.replace(seed=1))
    assert not np.array_equal(a.depth, c.depth)
    np.testing.assert_array_equal(depth, before[0])
    np.testing.assert_array_equal(rgb, before[1])


def test_rgbd_warp_runs_with_neighbours_and_auto_stop_keeps_the_best():
    gt, depth = slanted_plane()
    rgb = np.random.default_rng(0).random((32, 48, 3)).astype(np.float32)
    ref = Camera.from_fov(48, 32, 60.0)
    nbr = Camera(ref.K, look_at([0.1, 0, 0], [0.1, 0, 3]), 48, 32)
    config = FitConfig(iterations=40, auto_stop=True, patience=10, eval_every=5, **TINY)
    result = complete_depth(rgb, depth, ref, [(rgb, nbr)], variant="rgbd+warp", config=config, gt_depth=gt)
    assert {"disp", "rgb", "warp"} <= set(result.history)
    assert result.best_iteration <= result.iterations <= 40
    held_out = result.history["held_out"]
    best_index = list(result.history["eval_iteration"]).index(result.best_iteration)
    assert held_out[best_index] == pytest.approx(np.min(held_out[: len(held_out)]))


@pytest.mark.parametrize("decays, expected", [
    # patience 30 at eval_every 10: the 3rd evaluation without a new best is a plateau
    (0, ["improved", "", "", "stop"]),
    (1, ["improved", "", "", "decay", "", "improved", "", "", "stop"]),
    (2, ["improved", "", "", "decay", "", "improved", "", "", "decay", "improved", "", "", "stop"]),
])
def test_plateau_stopper_events_by_hand(decays, expected):
    errors = [5.0, 5.0, 6.0, 5.5, 5.2, 4.0, 4.0, 4.1, 4.0, 3.9, 4.5, 4.5, 4.5]
    stopper = PlateauStopper(patience=30, eval_every=10, decays=decays)
    events = []
    for error in errors:
        events.append(stopper.update(error))
        if events[-1] == "stop":
            break
    assert events == expected


def test_the_stoppers_earliest_and_expected_stop_count_the_plateaus_still_to_come():
    from ddp_lite.method.time_left import EXPECTED_STOP_SHARE, RUN_AFTER_CUT_SHARE, earliest_stop, expected_stop
    assert (EXPECTED_STOP_SHARE, RUN_AFTER_CUT_SHARE) == (0.8, 0.4)  # the figures below are worked out with these
    stopper = PlateauStopper(patience=50, eval_every=10, decays=1)
    stopper.update(1.0)  # a new best at iteration 10: a plateau needs 50 more, then the cut, then 50 more
    assert earliest_stop(stopper, 10, 600) == 110
    assert expected_stop(stopper, 10, 600) == 480  # before the cut: the usual share, 0.8 × 600
    for error in (2.0, 2.0, 2.0, 2.0):  # 40 without a best: 10 to the plateau, then 50 after the cut
        stopper.update(error)
    assert earliest_stop(stopper, 50, 600) == 110
    assert stopper.update(2.0) == "decay"  # iteration 60: the cut
    assert earliest_stop(stopper, 60, 600) == 110  # the next plateau could stop it at 110 ...
    assert expected_stop(stopper, 60, 600) == 300  # ... fits usually run 0.4 × 600 = 240 past the cut
    assert [stopper.update(0.9 - 0.01 * k) for k in range(30)] == ["improved"] * 30  # a new best up to iteration 360
    assert expected_stop(stopper, 360, 600) == 410  # past the cut + 240: the next plateau, 50 on
    assert earliest_stop(stopper, 60, 100) == expected_stop(stopper, 60, 100) == 100  # never past the cap
    late = PlateauStopper(patience=50, eval_every=10, decays=1)
    late.update(1.0)  # a best at 400 with no cut yet: the cut at 450 at the earliest, then 240 on: the cap
    assert expected_stop(late, 400, 600) == 600
    plain = PlateauStopper(patience=50, eval_every=10, decays=0)
    plain.update(1.0)  # no cut to come: the next plateau is the stop, at 450 at the earliest; the usual share, 480
    assert expected_stop(plain, 400, 600) == 480 and expected_stop(plain, 500, 600) == 550


def test_plateau_decay_continues_the_same_run_and_cuts_the_rate():
    gt, depth = slanted_plane()
    base = FitConfig(iterations=300, auto_stop=True, patience=10, eval_every=5, **TINY)
    plain = complete_depth(None, depth, variant="d", config=base)
    assert plain.iterations < 300, "the tiny case should plateau within 300 iterations"
    decayed = complete_depth(None, depth, variant="d", config=base.replace(plateau_decays=1))
    # same seed, same thread count: identical up to the first plateau, which now cuts lr instead of stopping
    assert list(decayed.history["lr_decay_iteration"]) == [plain.iterations]
    n = plain.iterations
    np.testing.assert_array_equal(decayed.history["loss"][:n], plain.history["loss"][:n])
    assert decayed.iterations > n
    # a rate cut by lr_gamma (0.01) moves the weights less: the loss changes less per step after the cut
    step = np.abs(np.diff(decayed.history["loss"]))
    assert np.median(step[n: n + 10]) < np.median(step[n - 10: n])


def test_merge_keeps_valid_input():
    depth = np.array([[1.0, np.nan], [np.nan, 4.0]], np.float32)
    np.testing.assert_array_equal(merge(depth, np.full((2, 2), 9.0, np.float32)), [[1.0, 9.0], [9.0, 4.0]])


def test_fit_image_inpaints_a_smooth_image():
    v, u = np.mgrid[0:32, 0:32] / 32.0
    image = np.stack([u, v, 0.5 * (u + v)], axis=2).astype(np.float32)
    mask = np.ones((32, 32), bool)
    mask[8:24, 8:24] = False
    result = fit_image(image * mask[..., None], mask, FitConfig(iterations=60, **TINY), clean=image)
    error = np.abs(result.image - image)[~mask].mean()
    assert error < 0.5 * np.abs(image[~mask]).mean()  # better than the zeros it was given
    assert result.history["psnr"][-1] > result.history["psnr"][0]


@pytest.mark.parametrize("make_bad, pattern", [
    (lambda d, r: (np.where(np.isnan(d), np.inf, d), r), "inf"),
    (lambda d, r: (-d, r), "positive"),
    (lambda d, r: (np.full_like(d, np.nan), r), "valid pixels"),
    (lambda d, r: (d[:, :-1], r), "rgb"),
    (lambda d, r: (np.ones(d.shape, np.int32), r), "float"),
    (lambda d, r: (d, r + 2.0), r"\[0, 1\]"),
    (lambda d, r: (d, r[..., :2]), r"\(H, W, 3\)"),
])
def test_bad_inputs_raise_naming_the_argument(make_bad, pattern):
    _, depth = slanted_plane()
    rgb = np.zeros((32, 48, 3), np.float32)
    depth, rgb = make_bad(depth, rgb)
    with pytest.raises((ValueError, TypeError), match=pattern):
        complete_depth(rgb, depth, variant="rgbd", config=FitConfig(iterations=1, **TINY))


def test_bad_variant_config_and_missing_neighbours():
    _, depth = slanted_plane()
    rgb = np.zeros((32, 48, 3), np.float32)
    with pytest.raises(ValueError, match="variant"):
        complete_depth(rgb, depth, variant="rgb")
    with pytest.raises(ValueError, match="neighbor"):
        complete_depth(rgb, depth, variant="rgbd+warp", config=FitConfig(iterations=1, **TINY))
    with pytest.raises(ValueError, match="config.lr"):
        complete_depth(rgb, depth, variant="d", config=FitConfig(lr=-1.0))
    with pytest.raises(ValueError, match="gt_depth"):
        complete_depth(rgb, depth, variant="d", gt_depth=np.zeros((3, 3)), config=FitConfig(iterations=1, **TINY))


def test_warm_start_begins_where_the_previous_fit_ended():
    gt, depth = slanted_plane()
    rgb = np.zeros((32, 48, 3), np.float32)
    config = FitConfig(iterations=30, **TINY)
    first = complete_depth(rgb, depth, variant="d", config=config)
    warm = complete_depth(rgb, depth, variant="d", config=config.replace(iterations=2), init=first)
    cold = complete_depth(rgb, depth, variant="d", config=config.replace(iterations=2))
    assert warm.history["loss"][0] < 0.2 * cold.history["loss"][0]
    with pytest.raises(ValueError, match="init"):
        complete_depth(rgb, depth, variant="rgbd", config=config.replace(iterations=1), init=first)


def test_bfloat16_and_channels_last_still_fill_the_hole():
    gt, depth = slanted_plane()
    holes = np.isnan(depth)
    config = FitConfig(iterations=60, bf16=True, **TINY)  # fills the hole to ~0.2x nearest by then
    result = complete_depth(np.zeros((32, 48, 3), np.float32), depth, variant="d", config=config,
                            options=RunOptions(channels_last=True))
    rmse = float(np.sqrt(np.mean((result.depth[holes] - gt[holes]) ** 2)))
    assert rmse < 0.7 * float(np.sqrt(np.mean((nearest_fill(depth)[holes] - gt[holes]) ** 2)))


def test_variant_table_is_the_papers():
    """Every per-variant difference comes from one record: γ, output channels, needs, iterations."""
    from ddp_lite.method.profiles import get_profile
    from ddp_lite.method.paper.variants import VARIANTS, get_variant
    assert VARIANTS == ("d", "rgbd", "rgbd+warp")
    d, rgbd, warp = (get_variant(name) for name in VARIANTS)
    assert d.loss_weights((0.5, 0.5)) == (1.0, 0.0, 0.0) and d.out_channels == 1
    assert rgbd.loss_weights() == (0.98, 0.01, 0.0) and rgbd.out_channels == 4
    assert warp.loss_weights()[:2] == (0.96, 0.02) and warp.loss_weights()[2] == pytest.approx(0.02)
    assert warp.loss_weights((0.9, 0.05))[2] == pytest.approx(0.05)
    assert [v.needs_neighbors for v in (d, rgbd, warp)] == [False, False, True]
    assert FitConfig().resolved_iterations("d") == 6000 and FitConfig().resolved_iterations("rgbd+warp") == 16000
    paper = get_profile("paper")
    assert paper.iterations_for("d") == 6000 and paper.iterations_for(warp) == 16000
    assert get_profile(paper) is paper
    with pytest.raises(ValueError, match="variant must be one of"):
        get_variant("rgb")


def test_for_profile_copies_every_shared_field_and_derives_the_rest():
    """One source of fit settings: a Profile field named like a FitConfig field reaches the config."""
    import dataclasses
    from ddp_lite.method.profiles import PROFILES
    for profile in PROFILES.values():
        for variant in ("d", "rgbd+warp"):
            config = FitConfig.for_profile(profile, variant=variant)
            iterations = profile.iterations_depth_only if variant == "d" else profile.iterations
            assert config.paper.iterations == iterations and config.paper.channels == profile.channels
            assert config.paper.lr_milestones == profile.milestones(iterations)
            flat = config.flat()
            for field in dataclasses.fields(profile):
                if field.name in flat and field.name not in ("channels", "iterations", "lr_milestones"):
                    assert flat[field.name] == getattr(profile, field.name), field.name
    assert FitConfig.for_profile("ci", net="skip").paper.channels == PROFILES["ci"].skip_channels
    assert FitConfig.for_profile("ci", lr=0.5).paper.lr == 0.5  # overrides win


def test_the_front_door_lists_what_users_call_and_hands_on_nothing_else():
    import importlib

    import ddp_lite
    assert {"complete_depth", "FitConfig", "get_profile", "get_recipe", "make_scene", "Camera"} <= set(ddp_lite.__all__)
    for name in ddp_lite.__all__:  # each is its own module's object, importable from there
        module = importlib.import_module(f"ddp_lite.{ddp_lite._FRONT_DOOR[name]}")
        assert getattr(ddp_lite, name) is getattr(module, name) and name in module.__all__
    # building blocks and modules by their own names no longer pass through the package
    for name in ("pixel_grid", "make_noise", "masked_l1", "build_net", "ssim", "complete_depth_coarse_to_fine",
                 "metrics", "baselines", "recipes", "loop"):
        assert not hasattr(ddp_lite, name), name
