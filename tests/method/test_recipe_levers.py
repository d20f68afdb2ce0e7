"""The recipe levers of the quality study: UNet down/up-sampling and padding, the cosine schedule,
ensembles of seeds and the disparity margin. Each is checked against an independent reference."""
import contextlib
import math

import os

import numpy as np
import pytest
import torch
import torch.nn.functional as F

from ddp_lite.method.paper.disparity import DisparityTransform
from ddp_lite.method.config import FitConfig
from ddp_lite.method.paper.nets import UNet
from ddp_lite.method.complete import complete_depth
from ddp_lite.method.paper.nets import _conv
from conftest import TINY, plane_with_hole, tilted_plane


@pytest.mark.parametrize("down", ["stride", "pool"])
@pytest.mark.parametrize("up", ["bilinear", "nearest"])
@pytest.mark.parametrize("pad", ["reflect", "zeros"])
def test_unet_options_keep_any_size(down, up, pad):
    net = UNet(16, 4, (8, 8, 8), down=down, up=up, pad=pad)
    out = net(torch.rand(1, 16, 19, 27))
    assert out.shape == (1, 4, 19, 27) and 0 <= out.min() and out.max() <= 1


def test_pool_down_sampling_is_a_max_pool_then_a_conv():
    net = UNet(4, 1, (4, 6), down="pool")
    block = net.downs[0]
    x = torch.rand(1, 4, 8, 8)
    # the first layer of the block is a 2×2 max-pool: compare with the plain functional form
    assert torch.equal(block[0](x), F.max_pool2d(x, 2))
    assert block[1][1].stride == (1, 1)


def test_zero_padded_conv_equals_an_explicitly_zero_padded_input():
    torch.manual_seed(0)
    block = _conv(3, 5, pad="zeros")
    x = torch.rand(1, 3, 7, 9)
    conv = block[1]
    expected = F.conv2d(F.pad(x, (1, 1, 1, 1)), conv.weight)
    assert torch.allclose(conv(block[0](x)), expected, atol=1e-6)


def test_reflect_padding_default_is_unchanged():
    block = _conv(3, 5)
    assert isinstance(block[0], torch.nn.ReflectionPad2d) and block[1].padding == (0, 0)


def test_bad_unet_option_names_the_argument():
    with pytest.raises(ValueError, match="up"):
        UNet(16, 4, (8, 8), up="cubic")
    with pytest.raises(ValueError, match="config.schedule"):
        FitConfig(schedule="linear").validate()
    with pytest.raises(ValueError, match="config.ensemble"):
        FitConfig(ensemble=0).validate()


def test_cosine_schedule_follows_the_closed_form():
    _, depth = plane_with_hole()
    config = FitConfig(**TINY, iterations=20, schedule="cosine")
    result = complete_depth(None, depth, variant="d", config=config)
    expected = [0.5 * 1e-2 * (1 + math.cos(math.pi * t / 20)) for t in range(20)]  # lr at step t
    assert np.allclose(result.history["lr"], expected, rtol=1e-6)
    step = complete_depth(None, depth, variant="d", config=config.replace(schedule="step", lr_milestones=(10,),
                                                                            lr_gamma=0.1))
    assert np.allclose(step.history["lr"], [1e-2] * 10 + [1e-3] * 10)
    assert np.isfinite(result.disparity).all() and not np.allclose(result.disparity, step.disparity)


@contextlib.contextmanager
def one_thread():
    threads = torch.get_num_threads()
    torch.set_num_threads(1)
    try:
        yield
    finally:
        torch.set_num_threads(threads)


def test_ensemble_members_run_side_by_side_with_the_numbers_of_one_thread_in_turn():
    from ddp_lite.method.runtime.options import RunOptions
    from ddp_lite.method.runtime.side_by_side import side_by_side_workers

    def parallel_members(config, variant, shape, n_neighbors, callback):  # what complete_depth asks for them
        return side_by_side_workers(config, RunOptions(), variant, shape, n_neighbors, config.combination.ensemble,
                                    callback)
    _, depth = plane_with_hole()
    rgb = np.random.default_rng(0).random(depth.shape + (3,)).astype(np.float32)
    config = FitConfig(**TINY, iterations=12, ensemble=2, auto_stop=True, patience=20, eval_every=2)
    threads = torch.get_num_threads()
    torch.set_num_threads(2)
    try:
        assert parallel_members(config, "rgbd", depth.shape, 0, callback=None) == 2
        assert parallel_members(config, "rgbd", depth.shape, 0, callback=lambda *a: None) == 1
        side_by_side = complete_depth(rgb, depth, variant="rgbd", config=config)
        assert torch.get_num_threads() == 2  # restored
        torch.set_num_threads(1)
        assert parallel_members(config, "rgbd", depth.shape, 0, callback=None) == 1
        in_turn = complete_depth(rgb, depth, variant="rgbd", config=config)
    finally:
        torch.set_num_threads(threads)
    assert np.array_equal(side_by_side.disparity, in_turn.disparity)
    assert np.array_equal(side_by_side.rgb, in_turn.rgb)
    assert side_by_side.iterations == in_turn.iterations


def test_ensemble_is_the_mean_disparity_of_its_seeds():
    gt, depth = plane_with_hole()
    config = FitConfig(**TINY, iterations=8)
    transform = DisparityTransform.from_depth(depth)
    with one_thread():  # as each member of an ensemble runs, so the numbers match exactly
        members = [complete_depth(None, depth, variant="d", config=config.replace(seed=s), transform=transform)
                   for s in (3, 4, 5)]
    ensemble = complete_depth(None, depth, variant="d", config=config.replace(seed=3, ensemble=3), transform=transform)
    expected = np.mean([m.disparity for m in members], axis=0)
    assert np.allclose(ensemble.disparity, expected, atol=1e-6)
    assert np.allclose(ensemble.depth, transform.to_depth(expected), rtol=1e-5)
    assert ensemble.iterations == 3 * 8 and ensemble.fits == 3 and members[0].fits == 1
    assert ensemble.best_iteration == members[0].best_iteration  # the first fit's, as documented
    assert not np.allclose(members[0].disparity, members[1].disparity)  # the seeds really differ


def test_disparity_margin_sets_the_default_transform_range():
    _, depth = plane_with_hole()
    valid = depth[np.isfinite(depth)]
    lo, hi = np.percentile(valid, [0.5, 99.5])
    result = complete_depth(None, depth, variant="d", config=FitConfig(**TINY, iterations=2, disparity_margin=1.5))
    assert result.transform.d_min == pytest.approx(lo / 1.5) and result.transform.d_max == pytest.approx(hi * 1.5)


def test_smoothness_is_zero_on_a_plane_and_hand_computed_on_a_parabola():
    from ddp_lite.method.kit.hole_losses import smoothness_loss, smoothness_weights
    H, W = 12, 16
    v, u = torch.meshgrid(torch.arange(H, dtype=torch.float64), torch.arange(W, dtype=torch.float64), indexing="ij")
    plane = (0.2 + 0.01 * u + 0.02 * v)[None, None]  # disparity affine in (u, v): a plane
    flat_image = torch.zeros(1, 3, H, W, dtype=torch.float64)
    everywhere = torch.ones(1, 1, H, W, dtype=torch.bool)
    weights = smoothness_weights(flat_image, everywhere)
    assert smoothness_loss(plane, weights).item() == pytest.approx(0.0, abs=1e-12)
    a = 0.003
    parabola = (a * u ** 2)[None, None]  # ∂²/∂u² = 2a exactly for second differences, ∂²/∂v² = 0
    n_x, n_y = H * (W - 2), (H - 2) * W  # pixels where each second difference exists
    expected = 2 * a * n_x / (n_x + n_y)
    assert smoothness_loss(parabola, weights).item() == pytest.approx(expected, rel=1e-9)


def test_smoothness_weights_relax_at_colour_edges_and_vanish_outside_the_region():
    from ddp_lite.method.kit.hole_losses import smoothness_weights
    image = torch.zeros(1, 3, 6, 8)
    image[..., 4:] = 1.0  # a vertical colour edge between columns 3 and 4
    region = torch.ones(1, 1, 6, 8, dtype=torch.bool)
    region[..., 0, :] = False
    w = smoothness_weights(image, region, edge=10.0)
    # along x at columns 3 and 4 the central difference of grey is 1/2: weight exp(-5)
    assert torch.allclose(w[0, 0, 1:, 3], torch.full((5,), math.exp(-5.0)))
    assert torch.allclose(w[0, 0, 1:, 2], torch.ones(5))
    assert torch.all(w[0, :, 0] == 0)  # outside the region
    assert torch.all(w[0, 0, :, [0, -1]] == 0) and torch.all(w[0, 1, [0, -1], :] == 0)  # no second difference


def test_rgb_edge_guide_sees_an_edge_between_colours_of_equal_brightness_that_grey_misses():
    from ddp_lite.method.kit.hole_losses import smoothness_weights
    image = torch.zeros(1, 3, 5, 8)
    image[0, 0, :, :4] = 0.9  # red left half, green right half: grey 0.3 on both sides
    image[0, 1, :, 4:] = 0.9
    region = torch.ones(1, 1, 5, 8, dtype=torch.bool)
    grey = smoothness_weights(image, region, edge=10.0, guide="grey")
    rgb = smoothness_weights(image, region, edge=10.0, guide="rgb")
    assert torch.allclose(grey[0, 0, :, 1:-1], torch.ones(5, 6))  # no grey edge anywhere
    # columns 3 and 4 straddle the edge: each channel changes by 0.9, half of it per pixel
    assert torch.allclose(rgb[0, 0, :, 3:5], torch.full((5, 2), math.exp(-10.0 * 0.45)))
    assert torch.allclose(rgb[0, 0, :, [1, 2, 5, 6]], torch.ones(5, 4))
    assert torch.allclose(rgb[0, 1, 1:-1], torch.ones(3, 8))  # nothing changes along y
    with pytest.raises(ValueError, match="guide"):
        smoothness_weights(image, region, guide="colour")


def test_structure_edge_guide_ignores_fine_texture_and_keeps_a_strong_edge():
    from skimage.restoration import denoise_tv_chambolle

    from ddp_lite.method.kit.hole_losses import STRUCTURE_TV_WEIGHT, smoothness_weights
    rng = np.random.default_rng(0)
    grey = np.where(np.arange(32) < 16, 0.2, 0.8)[None, :].repeat(24, 0)  # a step between columns 15 and 16
    grey = grey + 0.04 * rng.standard_normal(grey.shape)  # fine texture on both surfaces
    image = torch.from_numpy(np.repeat(grey[None, None], 3, axis=1)).float()  # (1, 3, 24, 32)
    region = torch.ones(1, 1, 24, 32, dtype=torch.bool)
    raw = smoothness_weights(image, region, edge=300.0, guide="grey")
    structure = smoothness_weights(image, region, edge=300.0, guide="structure")
    inside = (slice(2, -2), [4, 5, 6, 7, 24, 25, 26, 27])  # texture only, away from the step and the border
    assert raw[0, 0][inside].mean() < 0.2  # the texture switches the raw guide off ...
    assert structure[0, 0][inside].mean() > 0.5  # ... not the structure guide
    assert structure[0, 0, 2:-2, 15:17].max() < 1e-6  # the step still relaxes both
    # the weights are exp(-edge · half the central difference) of scikit-image's ROF denoising of the grey image
    smooth = denoise_tv_chambolle(image[0].mean(0).double().numpy(), weight=STRUCTURE_TV_WEIGHT)
    expected = np.exp(-300.0 * np.abs(smooth[:, 2:] - smooth[:, :-2]) / 2)
    assert np.allclose(structure[0, 0, 1:-1, 1:-1].numpy(), expected[1:-1], atol=1e-5)


def test_flatness_is_zero_on_a_constant_and_hand_computed_on_a_ramp():
    from ddp_lite.method.kit.hole_losses import flatness_loss, smoothness_weights
    H, W = 12, 16
    v, u = torch.meshgrid(torch.arange(H, dtype=torch.float64), torch.arange(W, dtype=torch.float64), indexing="ij")
    weights = smoothness_weights(torch.zeros(1, 3, H, W, dtype=torch.float64), torch.ones(1, 1, H, W, dtype=torch.bool))
    assert flatness_loss(torch.full((1, 1, H, W), 0.4, dtype=torch.float64), weights).item() == 0.0
    ramp = (0.2 + 0.01 * u - 0.03 * v)[None, None]  # |∂/∂u| = 0.01, |∂/∂v| = 0.03 everywhere
    n_x, n_y = H * (W - 2), (H - 2) * W  # pixels with weight 1 along x and along y (0 on the border)
    expected = (0.01 * n_x + 0.03 * n_y) / (n_x + n_y)
    assert flatness_loss(ramp, weights).item() == pytest.approx(expected, rel=1e-9)


def test_flatness_continues_a_border_hole_flat_where_curvature_alone_carries_the_slope():
    # a ramp in x whose last columns are a hole at the image border: the curvature term lets the
    # ramp go on; the first-order term pulls the border hole toward the last valid value
    H, W = 16, 32
    u = np.arange(W, dtype=np.float32)[None, :].repeat(H, 0)
    gt = 1.0 / (0.3 + 0.02 * u)  # metres: disparity rises along x
    depth = gt.copy()
    depth[:, 22:] = np.nan
    transform = DisparityTransform.from_depth(depth)
    last_valid = transform.to_disparity(depth[:, 21]).mean()

    def border_mean(**weights):
        config = FitConfig(**TINY, iterations=60, **weights)
        result = complete_depth(None, depth, variant="d", config=config, transform=transform)
        return float(result.disparity[:, 26:].mean())

    assert abs(border_mean(smoothness=1.0, flatness=1.0) - last_valid) < abs(border_mean(smoothness=1.0) - last_valid)


def test_flatness_region_is_the_border_holes_and_a_rim_of_the_enclosed_ones_by_brute_force():
    from ddp_lite.method.kit.hole_losses import flatness_region
    rng = np.random.default_rng(3)
    holes = rng.random((20, 24)) < 0.03  # scattered pixels, some at the border
    holes[5:14, 6:17] = True  # enclosed
    holes[0:4, 18:24] = True  # at the border
    reach = 2.5
    # the reference: for each hole pixel the distance to the nearest non-hole pixel by brute force,
    # and its component by a flood fill over 4-neighbours
    valid_yx = np.argwhere(~holes)
    expected = np.zeros_like(holes)
    seen = np.zeros_like(holes)
    for start in map(tuple, np.argwhere(holes)):
        if seen[start]:
            continue
        component, stack = [], [start]
        seen[start] = True
        while stack:
            y, x = stack.pop()
            component.append((y, x))
            for ny, nx in ((y - 1, x), (y + 1, x), (y, x - 1), (y, x + 1)):
                if 0 <= ny < 20 and 0 <= nx < 24 and holes[ny, nx] and not seen[ny, nx]:
                    seen[ny, nx] = True
                    stack.append((ny, nx))
        border = any(y in (0, 19) or x in (0, 23) for y, x in component)
        for y, x in component:
            nearest = np.sqrt(((valid_yx - (y, x)) ** 2).sum(1)).min()
            expected[y, x] = border or nearest <= reach
    region = flatness_region(holes, reach)
    np.testing.assert_array_equal(region, expected)
    assert region[0:4, 18:24].all() and not region[9, 11] and region[5, 11]  # border hole; centre; rim


def test_flatness_reach_zero_leaves_an_enclosed_hole_to_the_curvature_term_alone():
    # every hole pixel is ≥ 1 px from valid depth, so reach 0 takes the first-order term out of an
    # enclosed hole: the fit is the one without the term, to the bit; the full term changes it
    gt, depth = plane_with_hole()
    transform = DisparityTransform.from_depth(depth)
    fit = lambda **c: complete_depth(None, depth, variant="d", transform=transform,
                                     config=FitConfig(**TINY, iterations=10, smoothness=1.0, **c)).disparity
    without = fit()
    np.testing.assert_array_equal(fit(flatness=0.6, flatness_reach=0.0), without)
    assert not np.array_equal(fit(flatness=0.6), without)


def test_step_reach_switches_the_hole_terms_off_beside_a_depth_step_and_nowhere_else():
    # a hole in a gently tilted plane (depth within ±15 % over 12 px: no step): the guard changes nothing
    depth = tilted_plane(24, 32, slope=0.005)
    depth[8:16, 10:20] = np.nan
    transform = DisparityTransform.from_depth(depth)
    fit = lambda d, t, **c: complete_depth(None, d, variant="d", transform=t,
                                           config=FitConfig(**TINY, iterations=10, **c)).disparity
    terms = dict(smoothness=1.0, flatness=0.6)
    np.testing.assert_array_equal(fit(depth, transform, step_reach=6.0, **terms), fit(depth, transform, **terms))
    # a band of holes between a near (1 m) and a far (2 m) half: every hole pixel sees both sides
    # within 6 px, so the fit is the one without hole terms, to the bit
    step = np.where(np.arange(32)[None, :] < 16, 1.0, 2.0) * np.ones((24, 1))
    step[:, 13:19] = np.nan
    step_transform = DisparityTransform.from_depth(step)
    without = fit(step, step_transform)
    np.testing.assert_array_equal(fit(step, step_transform, step_reach=6.0, **terms), without)
    assert not np.array_equal(fit(step, step_transform, **terms), without)


def test_smoothness_fills_a_hole_in_a_plane_better_than_without():
    gt, depth = plane_with_hole()
    base = FitConfig(**TINY, iterations=60)
    transform = DisparityTransform.from_depth(depth)
    holes = ~np.isfinite(depth)

    def hole_error(config):
        result = complete_depth(None, depth, variant="d", config=config, transform=transform)
        return np.sqrt(np.mean((transform.to_disparity(result.depth) - transform.to_disparity(gt))[holes] ** 2))

    assert hole_error(base.replace(smoothness=1.0)) < 0.5 * hole_error(base)


def test_bf16_none_follows_the_cpu_flags():
    from ddp_lite.method.runtime.device import _cpu_has_native_bf16, use_bf16
    cpu = torch.device("cpu")
    assert use_bf16(True, cpu) is True and use_bf16(False, cpu) is False
    try:
        with open("/proc/cpuinfo") as handle:
            text = handle.read()
    except OSError:
        text = ""  # not Linux: no flags to read, so never bf16 by default
    native = ("avx512_bf16" in text or "amx_bf16" in text) and torch.backends.cpu.get_cpu_capability() != "AVX2"
    if os.environ.get("ONEDNN_MAX_CPU_ISA", "ALL").upper() in ("AVX2", "AVX", "SSE41"):
        native = False  # kernels capped at AVX2, as on a laptop: bfloat16 would be emulated
    assert use_bf16(None, cpu) == native == _cpu_has_native_bf16()
    assert use_bf16(None, torch.device("meta")) is False


@pytest.mark.parametrize("shape", ["pixels", "blobs"])
def test_held_out_takes_its_share_of_valid_pixels_only(shape):
    from ddp_lite.method.stopping import held_out_mask
    valid = np.ones((48, 64), bool)
    valid[:, :20] = False  # a hole: never held out
    held = held_out_mask(valid, 0.05, seed=3, shape=shape)
    assert not held[~valid].any()
    assert abs(held.sum() / valid.sum() - 0.05) < 0.02
    np.testing.assert_array_equal(held, held_out_mask(valid, 0.05, seed=3, shape=shape))  # seeded


def test_held_out_blobs_are_patches_not_scattered_pixels():
    from scipy import ndimage
    from ddp_lite.method.stopping import held_out_mask
    valid = np.ones((96, 128), bool)
    pixels, blobs = (held_out_mask(valid, 0.05, seed=0, shape=s) for s in ("pixels", "blobs"))
    # 4-connected components: ~600 scattered pixels are mostly alone; blobs are a handful of patches
    assert ndimage.label(pixels)[1] > 400
    assert ndimage.label(blobs)[1] < 30
    # a blob pixel's 4 neighbours are mostly held out too (interior), a scattered pixel's almost never
    inner = ndimage.binary_erosion(blobs)
    assert inner.sum() > 0.4 * blobs.sum()


def test_bad_held_out_shape_names_the_argument():
    with pytest.raises(ValueError, match="config.held_out_shape"):
        FitConfig(held_out_shape="rings").validate()


def test_meshgrid_input_is_the_pixel_coordinates_then_seeded_noise():
    from ddp_lite.method.paper.nets import make_input
    H, W = 5, 9
    a, b = make_input("meshgrid", 6, H, W, seed=0), make_input("meshgrid", 6, H, W, seed=1)
    assert a.shape == (1, 6, H, W)
    rows, cols = np.mgrid[0:H, 0:W]
    assert np.allclose(a[0, 0].numpy(), cols / (W - 1)) and np.allclose(a[0, 1].numpy(), rows / (H - 1))
    assert torch.equal(a[:, :2], b[:, :2])  # the grid does not depend on the seed ...
    assert not torch.equal(a[:, 2:], b[:, 2:])  # ... the noise channels do
    assert 0.0 <= float(a[:, 2:].min()) and float(a[:, 2:].max()) < 0.1  # DIP's noise range
    assert make_input("meshgrid", 2, 1, 1).tolist() == [[[[0.0]], [[0.0]]]]  # one pixel: no division by zero


def test_meshgrid_input_runs_a_fit_and_bad_values_name_the_argument():
    from ddp_lite.method.paper.nets import make_input
    depth = tilted_plane(12, 16)
    depth[4:8, 5:11] = np.nan
    result = complete_depth(None, depth, variant="d", config=FitConfig(**TINY, iterations=3, net_input="meshgrid"))
    assert np.isfinite(result.depth).all()
    with pytest.raises(ValueError, match="net_input"):
        FitConfig(net_input="grid").validate()
    with pytest.raises(ValueError, match="noise_channels.*meshgrid"):
        FitConfig(net_input="meshgrid", noise_channels=1).validate()
    with pytest.raises(ValueError, match="at least 2 channels"):
        make_input("meshgrid", 1, 4, 4)


def test_image_channels_are_the_image_blurred_like_scipys_gaussian_filter_then_scaled():
    from scipy.ndimage import gaussian_filter
    from ddp_lite.method.kit.net_inputs import image_channels
    image = np.random.default_rng(0).random((1, 3, 9, 13)).astype(np.float32)
    for blur in (1.0, 2.0):
        reference = gaussian_filter(image, sigma=(0, 0, blur, blur), mode="nearest", truncate=3.0)
        got = image_channels(torch.from_numpy(image), 0.5, blur).numpy()
        assert np.allclose(got, 0.5 * reference, atol=1e-6)
    assert torch.equal(image_channels(torch.from_numpy(image), 2.0, 0.0), 2.0 * torch.from_numpy(image))


def test_image_input_feeds_the_colour_image_to_variants_that_see_it_and_not_to_depth_only():
    from ddp_lite.method import loop
    from ddp_lite.method.kit.net_inputs import image_channels
    depth = tilted_plane(12, 16)
    depth[4:8, 5:11] = np.nan
    rgb = np.random.default_rng(1).random((12, 16, 3)).astype(np.float32)
    seen = []
    build = loop.build

    def spy(config, out_channels, height, width, device, init_state=None, noise=None, image=None):
        net, net_input = build(config, out_channels, height, width, device, init_state, noise, image)
        seen.append((net, net_input))
        return net, net_input

    loop.build = spy
    try:
        config = FitConfig(**TINY, iterations=2, net_input="meshgrid", noise_channels=2, image_input=0.5, image_blur=1.0)
        complete_depth(rgb, depth.copy(), variant="rgbd", config=config)
        complete_depth(rgb, depth.copy(), variant="d", config=config)
    finally:
        loop.build = build
    (net_rgbd, input_rgbd), (net_d, input_d) = seen
    first_conv = [next(m for m in net.modules() if isinstance(m, torch.nn.Conv2d)) for net in (net_rgbd, net_d)]
    assert input_rgbd.shape == (1, 5, 12, 16) and [c.in_channels for c in first_conv] == [5, 2]
    # channels 2-4: the view's colours, blurred and scaled; 0-1: the coordinates as without it
    expected = image_channels(torch.from_numpy(rgb).permute(2, 0, 1)[None], 0.5, 1.0)
    assert torch.allclose(input_rgbd[:, 2:], expected, atol=1e-6)
    assert torch.equal(input_rgbd[:, :2], input_d)
    assert input_d.shape == (1, 2, 12, 16)  # depth-only sees no colour, not even as input


def test_start_at_makes_the_first_depth_output_the_given_disparity_and_leaves_the_colour_channels():
    from ddp_lite.method.kit.net_inputs import start_at
    torch.manual_seed(3)
    net, x = UNet(2, 4, channels=(4, 8)), torch.rand(1, 2, 10, 14)
    before = net(x).detach()
    start = torch.from_numpy(np.random.default_rng(0).uniform(0.05, 0.95, (1, 1, 10, 14)).astype(np.float32))
    start_at(net, start)
    for inputs in (x, torch.rand(1, 2, 10, 14)):  # the start does not depend on the net's input
        assert torch.allclose(net(inputs).detach()[:, :1], start, atol=1e-5)
    assert torch.allclose(net(x).detach()[:, 1:], before[:, 1:], atol=1e-6)
    with pytest.raises(TypeError, match="config.fill_start"):
        FitConfig(fill_start=1).validate()


def test_fill_start_begins_the_fit_at_the_colorization_fill_of_the_input():
    from ddp_lite.classical.guided_fills import fill_colorization
    depth = tilted_plane(12, 16)
    depth[4:8, 5:11] = np.nan
    rgb = np.random.default_rng(1).random((12, 16, 3)).astype(np.float32)
    transform = DisparityTransform.from_depth(depth)
    # the reference: colorization of the input's disparity (shifted positive, as the fills take metres)
    reference = transform.to_depth(fill_colorization(transform.to_disparity(depth) + 1.0, rgb) - 1.0)
    holes = np.isnan(depth)
    for fill_start in (False, True):
        config = FitConfig(**{**TINY, "lr": 1e-9}, iterations=1, auto_stop=False, fill_start=fill_start)
        result = complete_depth(rgb, depth.copy(), variant="rgbd", config=config, transform=transform)
        error = np.abs(result.depth[holes] - reference[holes]).max()
        assert (error < 1e-3) == fill_start, (fill_start, error)
