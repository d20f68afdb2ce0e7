"""The self-validated blend of the kit's fit and the paper's (``FitConfig.blend_paper``): the ring it
holds out, the weight it picks, and the fit it returns, each against an independent reference."""
import numpy as np
import pytest
import torch

from ddp_lite.method.config import FitConfig
from ddp_lite.method.complete import complete_depth
from ddp_lite.method.kit.blend import (BLEND_WEIGHTS, FILL_SHARES, best_fill_share, best_weight, fill_held_out_mask,
                                  ring_width, validation_ring)
from ddp_lite.method.kit.recipes import get_recipe
from conftest import TINY, tilted_plane


def brute_force_distance_to_hole(valid):
    """(H, W) Euclidean distance of every pixel to the nearest hole pixel, by comparing all pairs."""
    ys, xs = np.nonzero(~valid)
    yy, xx = np.indices(valid.shape)
    return np.sqrt((yy[..., None] - ys) ** 2 + (xx[..., None] - xs) ** 2).min(axis=-1)


def test_the_ring_is_half_of_the_valid_pixels_within_its_width_of_a_hole():
    valid = np.ones((40, 56), bool)
    valid[12:20, 10:30] = False
    valid[30:34, 40:44] = False
    full = valid & (brute_force_distance_to_hole(valid) <= 2)
    ring = validation_ring(valid, seed=3, width=2)
    assert not (ring & ~full).any()  # only valid pixels, none further than 2 px from a hole
    assert ring.sum() == pytest.approx(0.5 * full.sum(), abs=1)  # half of them, by the field's median
    assert np.array_equal(validation_ring(valid, seed=3, width=2, share=1.0), full)
    assert np.array_equal(ring, validation_ring(valid, seed=3, width=2))  # seeded
    assert not np.array_equal(ring, validation_ring(valid, seed=4, width=2))
    assert not validation_ring(np.ones((40, 56), bool)).any()  # no hole, no ring


def test_the_ring_comes_in_patches_not_scattered_pixels():
    valid = np.ones((96, 128), bool)
    valid[30:60, 30:90] = False
    ring = validation_ring(valid, seed=0)
    # along the hole's top edge (row 29, a ring pixel next to the hole), kept pixels come in runs
    row = ring[29, 30:90].astype(int)
    runs = np.count_nonzero(np.diff(row) == 1) + row[0]
    assert 0 < row.sum() < row.size and runs <= 4


def test_ring_width_follows_the_image_size():
    assert [ring_width((h, 2 * h)) for h in (24, 48, 96, 125, 512)] == [1, 1, 2, 2, 10]


def test_best_weight_is_the_least_squares_blend_on_the_grid():
    rng = np.random.default_rng(0)
    truth = rng.random((20, 20))
    kit, paper = truth + 0.3, truth - 0.1  # the blend w·0.3 − (1 − w)·0.1 is 0 at w = 0.25
    ring = rng.random((20, 20)) < 0.3
    weight, errors = best_weight(kit, paper, truth, ring)
    assert weight == 0.25
    expected = [abs(w * 0.3 - (1 - w) * 0.1) for w in BLEND_WEIGHTS]  # constant offsets: RMSE = |offset|
    assert np.allclose(errors, expected)
    # outside the ring nothing counts: a wild value there changes nothing
    kit[~ring] = 1e6
    assert best_weight(kit, paper, truth, ring)[0] == 0.25
    # a tie goes to the kit's fit
    assert best_weight(truth + 1.0, truth + 1.0, truth, ring)[0] == 1.0


def test_blend_weight_none_blends_the_two_fits_without_the_ring_by_the_ring():
    depth = tilted_plane(40, 48, slope=0.05)
    depth[10:30, 12:36] = np.nan  # a 20 × 24 hole: its ring (1 px at this size) has ~45 pixels
    rgb = np.random.default_rng(1).random(depth.shape + (3,)).astype(np.float32)
    given = depth.copy()
    config = FitConfig(**TINY, iterations=5, seed=2, smoothness=1.0, net_input="meshgrid", noise_channels=2)
    threads = torch.get_num_threads()
    torch.set_num_threads(1)
    try:
        blended = complete_depth(rgb, depth, variant="rgbd", config=config.replace(blend_paper=True, blend_weight=None))
        # by hand: the ring held out, the two recipes fitted on what is left, the weight from the ring
        ring = validation_ring(np.isfinite(depth), seed=2)
        held_out = np.where(ring, np.nan, depth)
        kit = complete_depth(rgb, held_out, variant="rgbd", config=config, transform=blended.transform)
        paper = complete_depth(rgb, held_out, variant="rgbd", transform=blended.transform,
                               config=config.replace(**get_recipe("paper").overrides))
    finally:
        torch.set_num_threads(threads)
    assert np.array_equal(depth, given, equal_nan=True)  # the caller's array is untouched
    assert ring.sum() > 20 and not np.array_equal(kit.disparity, paper.disparity)
    target = blended.transform.to_disparity(depth)
    errors = [np.sqrt(np.mean((w * kit.disparity[ring] + (1 - w) * paper.disparity[ring] - target[ring]) ** 2))
              for w in BLEND_WEIGHTS]
    weight = blended.history["blend_weight"]
    assert errors[BLEND_WEIGHTS.index(weight)] == pytest.approx(min(errors), rel=1e-6)
    assert np.allclose(blended.history["blend_ring_errors"], errors, rtol=1e-5)
    assert np.allclose(blended.disparity, weight * kit.disparity + (1 - weight) * paper.disparity, atol=1e-6)
    assert blended.fits == 2 and blended.iterations == kit.iterations + paper.iterations


def test_a_ring_blend_without_holes_is_one_plain_fit():
    depth = np.full((24, 32), 2.0, np.float32)
    config = FitConfig(**TINY, iterations=5)
    plain = complete_depth(None, depth, variant="d", config=config)
    blended = complete_depth(None, depth, variant="d", config=config.replace(blend_paper=True, blend_weight=None))
    assert np.array_equal(plain.disparity, blended.disparity) and blended.fits == 1


def test_a_blend_of_the_kit_fit_the_paper_fit_and_the_fill_is_their_weighted_mean():
    depth = tilted_plane(32, 40, slope=0.05)
    depth[8:20, 10:28] = np.nan
    rgb = np.random.default_rng(2).random(depth.shape + (3,)).astype(np.float32)
    thirds = FitConfig.for_profile("ci", variant="rgbd", recipe="kit", iterations=4,
                                   blend_paper=True, blend_weight=0.5, blend_fill=1 / 3)
    threads = torch.get_num_threads()
    torch.set_num_threads(1)
    try:
        blended = complete_depth(rgb, depth, variant="rgbd", config=thirds)
        kit = complete_depth(rgb, depth, variant="rgbd", transform=blended.transform,
                             config=FitConfig.for_profile("ci", variant="rgbd", recipe="kit", iterations=4,
                                                          blend_fill=0.0))  # the kit's fit alone
        paper = complete_depth(rgb, depth, variant="rgbd", transform=blended.transform,
                               config=FitConfig.for_profile("ci", variant="rgbd", recipe="paper",
                                                            iterations=4))
    finally:
        torch.set_num_threads(threads)
    fill = two_fills_disparity(depth, rgb, blended.transform)
    assert blended.history["blend_weight"] == 0.5 and blended.history["blend_fill"] == pytest.approx(1 / 3)
    assert not np.array_equal(kit.disparity, paper.disparity)
    assert np.allclose(blended.disparity, (kit.disparity + paper.disparity + fill) / 3, atol=1e-6)
    assert np.allclose(blended.rgb, 0.5 * (kit.rgb + paper.rgb), atol=1e-6)  # the fill has no colour
    assert blended.fits == 2


def test_the_photo_recipe_is_the_kit_fit_refined_then_the_kits_share_of_the_fill():
    from ddp_lite.classical.full_resolution import SMOOTHNESS_MEAN, refine_full_resolution
    depth = tilted_plane(32, 40, slope=0.05)
    depth[8:20, 10:28] = np.nan
    rgb = np.random.default_rng(2).random(depth.shape + (3,)).astype(np.float32)
    photo = FitConfig.for_profile("ci", variant="rgbd", recipe="photo", iterations=4)
    kit = FitConfig.for_profile("ci", variant="rgbd", recipe="kit", iterations=4)
    assert kit.holes.smoothness > 0 and kit.holes.flatness > 0
    kit_config = kit.replace(smoothness=0.0, flatness=0.0)
    assert photo == kit_config.replace(refine=True)  # the kit without its hole terms, and the solve
    result = complete_depth(rgb, depth, variant="rgbd", config=photo)
    alone = complete_depth(rgb, depth, variant="rgbd", transform=result.transform,
                           config=kit_config.replace(blend_fill=0.0))  # the same fit, neither refined nor mixed
    share = kit_config.combination.blend_fill
    sharp = np.mean([result.transform.to_disparity(refine_full_resolution(depth, rgb, alone.depth, sigma_xy=s, lam=lam))
                     for s, lam in SMOOTHNESS_MEAN], axis=0)  # the solve over four smoothness settings, averaged
    fill = two_fills_disparity(depth, rgb, result.transform)
    assert result.history["refined"] and result.history["blend_fill"] == share
    assert np.allclose(result.disparity, (1 - share) * sharp + share * fill, atol=1e-5)
    assert result.fits == 1


def test_refine_puts_a_blurred_depth_edge_back_on_the_colour_edge():
    # two planes, 1 m left of column 20 and 2 m right of it, with a black | white image: a fit that has
    # only run a few iterations blurs the step across the hole; the solve toward it, guided by the
    # image, must put the step at column 20 (the truth) and leave the valid input as it was
    truth = np.where(np.arange(40) < 20, 1.0, 2.0)[None, :].repeat(32, axis=0).astype(np.float32)
    rgb = np.zeros((32, 40, 3), np.float32)
    rgb[:, 20:] = 1.0
    depth = truth.copy()
    depth[8:24, 12:28] = np.nan
    config = FitConfig.for_profile("ci", variant="rgbd", recipe="kit", iterations=8, blend_fill=0.0)
    plain = complete_depth(rgb, depth, variant="rgbd", config=config)
    sharp = complete_depth(rgb, depth, variant="rgbd", config=config.replace(refine=True))
    holes = np.isnan(depth)

    def hole_error(result):
        return np.abs(1 / result.depth[holes] - 1 / truth[holes]).mean()  # 1/m
    assert hole_error(sharp) < 0.2 * hole_error(plain)
    assert np.array_equal(sharp.depth[~holes], depth[~holes])
    with pytest.raises(ValueError, match="config.refine needs the colour image"):
        complete_depth(None, depth, variant="d", config=config.replace(refine=True))
    with pytest.raises(TypeError, match="config.refine"):
        FitConfig(refine="yes").validate()
    assert not FitConfig.for_profile("ci", variant="d", recipe="photo").combination.refine  # depth only: no colour


def rim_of_holes(valid):
    """(H, W) bool: the valid pixels with a hole among their four neighbours, by shifting the hole mask."""
    hole = np.pad(~valid, 1)
    return valid & (hole[:-2, 1:-1] | hole[2:, 1:-1] | hole[1:-1, :-2] | hole[1:-1, 2:])


def test_a_stereo_input_is_read_without_the_rim_of_its_holes():
    from ddp_lite.method.kit.blend import trusted_depth
    depth = tilted_plane(20, 24, slope=0.05)
    depth[5:12, 6:15] = np.nan
    depth[16, 20] = np.nan  # a one-pixel hole has a rim too
    given = depth.copy()
    stereo = trusted_depth(depth, "stereo")
    expected = np.isnan(depth) | rim_of_holes(np.isfinite(depth))
    assert np.array_equal(np.isnan(stereo), expected)
    assert np.array_equal(stereo[~expected], depth[~expected])
    assert trusted_depth(depth) is depth and np.array_equal(depth, given, equal_nan=True)  # clean: all of it, untouched
    small = np.ones((4, 4), np.float32)
    small[1, 1] = np.nan  # the rim would leave fewer than 16 valid pixels: read as it is
    assert np.array_equal(trusted_depth(small, "stereo"), small, equal_nan=True)
    with pytest.raises(ValueError, match="source must be one of"):
        trusted_depth(depth, "kinect")
    with pytest.raises(ValueError, match="config.depth_source must be one of"):
        FitConfig(depth_source="sgbm").validate()


def test_a_stereo_photo_does_not_carry_a_wrong_rim_into_the_hole():
    # a matcher's rim: the valid pixels around the hole hold a nearer surface's depth (1.5 m on a 2 m
    # plane), as a stereo matcher's foreground fattening leaves them; the stereo photo reads past that rim
    # (the solves of SMOOTHNESS_STEREO and the fill on the trusted depth) and gives the rim back as given
    from ddp_lite.classical.full_resolution import SMOOTHNESS_STEREO, refine_full_resolution
    truth = tilted_plane(28, 36, slope=0.02) + 1.0
    depth = truth.copy()
    depth[8:20, 10:26] = np.nan
    rim = rim_of_holes(np.isfinite(depth))
    depth[rim] = 1.5
    rgb = np.random.default_rng(4).random(depth.shape + (3,)).astype(np.float32)
    photo = FitConfig.for_profile("ci", variant="rgbd", recipe="photo", iterations=8)
    clean = complete_depth(rgb, depth, variant="rgbd", config=photo)
    stereo = complete_depth(rgb, depth, variant="rgbd", config=photo.replace(depth_source="stereo"),
                            transform=clean.transform)
    holes = np.isnan(depth)

    def hole_error(result):
        return np.abs(1 / result.depth[holes] - 1 / truth[holes]).mean()  # 1/m
    assert hole_error(stereo) < 0.5 * hole_error(clean)
    assert np.allclose(stereo.depth[~holes], depth[~holes], rtol=1e-5)  # the wrong rim too, as given
    alone = complete_depth(rgb, depth, variant="rgbd", transform=clean.transform,
                           config=photo.replace(refine=False, blend_fill=0.0))
    trusted = np.where(rim, np.nan, depth)
    transform = clean.transform
    target = np.clip(alone.depth, np.nanmin(depth), np.nanmax(depth))  # the fit held to the input's range first
    sharp = np.mean([transform.to_disparity(refine_full_resolution(trusted, rgb, target, sigma_xy=s, lam=lam))
                     for s, lam in SMOOTHNESS_STEREO], axis=0)
    fill = two_fills_disparity(trusted, rgb, transform)
    share = photo.combination.blend_fill
    assert np.allclose(stereo.disparity[holes], ((1 - share) * sharp + share * fill)[holes], atol=1e-5)


def test_refine_does_not_keep_a_fit_that_ran_off_its_range_inside_a_hole():
    # a fit that matches every valid pixel but put the hole at 20 m on a 1.5-2.5 m plane (the end of its
    # disparity range): the solve starts from the fit clipped to the valid input's range, so the hole
    # comes back within the valid depth's range (unclipped, it stays at the far end of the disparity range)
    from dataclasses import replace
    from ddp_lite.method.kit.combine import refined
    truth = tilted_plane(28, 36, slope=0.03) + 0.5
    depth = truth.copy()
    depth[8:20, 10:26] = np.nan
    holes = np.isnan(depth)
    rgb = np.random.default_rng(5).random(depth.shape + (3,)).astype(np.float32)
    config = FitConfig.for_profile("ci", variant="rgbd", recipe="kit", iterations=4, blend_fill=0.0)
    result = complete_depth(rgb, depth, variant="rgbd", config=config)
    ran_off = replace(result, depth=np.where(holes, 20.0, truth).astype(np.float32))
    sharp = refined(ran_off, depth, rgb).depth
    lo, hi = np.nanmin(depth), np.nanmax(depth)
    assert np.all((sharp[holes] >= lo - 1e-4) & (sharp[holes] <= hi + 1e-4))
    assert np.allclose(sharp[~holes], depth[~holes], rtol=1e-5)  # as given, through the result's transform


def fill_case(seed):
    """A tilted plane with one hole, a random colour image and a short `ci` config of the fit alone: (depth, rgb, config)."""
    depth = tilted_plane(24, 32, slope=0.05)
    depth[6:16, 8:20] = np.nan
    rgb = np.random.default_rng(seed).random(depth.shape + (3,)).astype(np.float32)
    return depth, rgb, FitConfig.for_profile("ci", variant="rgbd", recipe="kit", iterations=6,
                                             blend_fill=0.0)


def two_fills_disparity(depth, rgb, transform):
    """The mean of the colorization fill and the bilateral solver's of 1/z, computed here from the two
    classical fills, in ``transform``'s disparity."""
    from ddp_lite.classical.guided_fills import fill_bilateral_solver, fill_colorization
    inverse = 1.0 / depth
    return transform.to_disparity(2.0 / (fill_colorization(inverse, rgb) + fill_bilateral_solver(inverse, rgb)))


def test_blend_fill_alone_mixes_one_fit_with_the_fill_and_needs_the_colour_image():
    depth, rgb, base = fill_case(3)
    mixed = complete_depth(rgb, depth, variant="rgbd", config=base.replace(blend_fill=0.25))
    alone = complete_depth(rgb, depth, variant="rgbd", config=base, transform=mixed.transform)
    fill = two_fills_disparity(depth, rgb, mixed.transform)
    assert np.allclose(mixed.disparity, 0.75 * alone.disparity + 0.25 * fill, atol=1e-6)
    assert np.allclose(mixed.depth, mixed.transform.to_depth(mixed.disparity))
    with pytest.raises(ValueError, match="config.blend_fill"):
        complete_depth(None, depth, variant="d", config=FitConfig.for_profile("ci", variant="d", blend_fill=0.25))
    for bad in (1.0, -0.1):
        with pytest.raises(ValueError, match="config.blend_fill"):
            FitConfig(blend_fill=bad).validate()


def test_coarse_to_fine_mixes_the_fill_into_its_full_size_result():
    from ddp_lite.method.coarse_to_fine import complete_depth_coarse_to_fine

    depth, rgb, base = fill_case(4)
    mixed = complete_depth_coarse_to_fine(rgb, depth, variant="rgbd", config=base.replace(blend_fill=0.2))
    alone = complete_depth_coarse_to_fine(rgb, depth, variant="rgbd", config=base, transform=mixed.transform)
    fill = two_fills_disparity(depth, rgb, mixed.transform)
    assert np.allclose(mixed.disparity, 0.8 * alone.disparity + 0.2 * fill, atol=1e-6)
    assert mixed.history["blend_fill"] == 0.2 and "stage_iterations" in mixed.history
    with pytest.raises(ValueError, match="config.blend_fill"):
        complete_depth_coarse_to_fine(None, depth, variant="d", config=base.replace(blend_fill=0.2))
    chosen = complete_depth_coarse_to_fine(rgb, depth, variant="rgbd", config=base.replace(blend_fill=None))
    assert chosen.history["blend_fill"] in FILL_SHARES and len(chosen.history["blend_fill_errors"]) == len(FILL_SHARES)


def test_best_fill_share_is_the_least_squares_share_on_the_grid():
    rng = np.random.default_rng(5)
    truth = rng.random((20, 20))
    fit, fill = truth + 0.15, truth - 0.6  # (1 − f)·0.15 − f·0.6 is 0 at f = 0.2
    held = rng.random((20, 20)) < 0.3
    share, errors = best_fill_share(fit, fill, truth, held)
    assert share == 0.2
    assert np.allclose(errors, [abs((1 - f) * 0.15 - f * 0.6) for f in FILL_SHARES])  # RMSE of a constant offset
    assert best_fill_share(truth + 1.0, truth + 1.0, truth, held)[0] == 0.0  # a tie goes to the fit
    assert best_fill_share(truth + 1.0, truth, truth, held)[0] == max(FILL_SHARES)  # at most the grid's largest


def test_the_fill_held_out_mask_is_blobs_of_one_twentieth_of_the_valid_pixels():
    from scipy import ndimage

    valid = np.ones((96, 128), bool)
    valid[30:60, 30:90] = False
    held = fill_held_out_mask(valid, seed=1)
    assert not (held & ~valid).any() and held.sum() == pytest.approx(0.05 * valid.sum(), rel=0.02)
    labels, count = ndimage.label(held)
    assert count < held.sum() / 10  # patches of tens of pixels, not scattered ones
    assert np.array_equal(held, fill_held_out_mask(valid, seed=1))
    assert not np.array_equal(held, fill_held_out_mask(valid, seed=2))


def test_blend_fill_none_chooses_the_share_on_depth_held_out_of_the_fit():
    depth, rgb, base = fill_case(6)
    given = depth.copy()
    chosen = complete_depth(rgb, depth, variant="rgbd", config=base.replace(blend_fill=None))
    assert np.array_equal(depth, given, equal_nan=True)  # the caller's array is untouched
    # by hand: the blobs held out of the fit, the fill of what is left, the share from the blobs
    held = fill_held_out_mask(np.isfinite(depth), seed=base.paper.seed)
    held_out = np.where(held, np.nan, depth)
    alone = complete_depth(rgb, held_out, variant="rgbd", config=base, transform=chosen.transform)
    target = chosen.transform.to_disparity(depth)
    fill_held = two_fills_disparity(held_out, rgb, chosen.transform)
    errors = [np.sqrt(np.mean(((1 - f) * alone.disparity[held] + f * fill_held[held] - target[held]) ** 2))
              for f in FILL_SHARES]
    share = chosen.history["blend_fill"]
    assert held.sum() > 10 and share in FILL_SHARES
    assert errors[FILL_SHARES.index(share)] == pytest.approx(min(errors), rel=1e-6)
    assert np.allclose(chosen.history["blend_fill_errors"], errors, rtol=1e-5)
    # the result mixes that share of the fill of the *whole* input into the fit without the blobs
    fill = two_fills_disparity(depth, rgb, chosen.transform)
    assert np.allclose(chosen.disparity, (1 - share) * alone.disparity + share * fill, atol=1e-6)


def test_blend_fill_none_without_enough_depth_to_hold_out_is_the_fit_alone():
    depth = np.full((24, 32), np.nan, np.float32)
    depth[:4, :6] = 2.0  # 24 valid pixels: too few to hold any out
    rgb = np.random.default_rng(0).random(depth.shape + (3,)).astype(np.float32)
    config = FitConfig(**TINY, iterations=5)
    alone = complete_depth(rgb, depth, variant="rgbd", config=config)
    chosen = complete_depth(rgb, depth, variant="rgbd", config=config.replace(blend_fill=None))
    assert np.array_equal(alone.disparity, chosen.disparity) and chosen.history["blend_fill"] == 0.0


def test_blend_paper_refuses_an_ensemble_and_a_non_bool():
    with pytest.raises(ValueError, match="config.blend_paper"):
        FitConfig(blend_paper=True, ensemble=2).validate()
    with pytest.raises(TypeError, match="config.blend_paper"):
        FitConfig(blend_paper="yes").validate()
    with pytest.raises(ValueError, match="config.blend_weight"):
        FitConfig(blend_paper=True, blend_weight=1.5).validate()


def test_the_equation_shows_the_blend_as_not_in_the_paper():
    from ddp_lite.method.equation import loss_equation
    thirds = loss_equation(FitConfig.for_profile("ci", variant="rgbd", recipe="kit", blend_paper=True,
                                                 blend_fill=1 / 3), "rgbd")
    photo = loss_equation(FitConfig.for_profile("ci", variant="rgbd", recipe="photo"), "rgbd")
    kit = loss_equation(FitConfig.for_profile("ci", variant="rgbd", recipe="kit", blend_fill=0.0), "rgbd")  # the fit alone
    photo_fit = loss_equation(FitConfig.for_profile("ci", variant="rgbd", recipe="photo", refine=False, blend_fill=0.0),
                              "rgbd")
    assert thirds.endswith("\\underbrace{\\hat Z = 0.333\\,Z + 0.333\\,Z_{\\mathrm{paper}} + 0.333\\,\\mathrm{fill}(Z_{\\mathrm{in}})}"
                           "_{\\text{not in the paper}}")
    assert photo.endswith("\\underbrace{\\hat Z = 0.75\\,\\mathcal{R}_I(Z) + 0.25\\,\\mathrm{fill}(Z_{\\mathrm{in}})}"
                          "_{\\text{not in the paper}}")
    assert thirds.startswith(kit) and photo.startswith(photo_fit) and "Z_{\\mathrm{paper}}" not in kit
