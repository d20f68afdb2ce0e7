"""The kit's steps after the fit give the same answer on one scene at two sizes: their pixel settings (the
solve's reach, the stereo rim's width, the fill's solver reach) scale with the image, and hold their tuned
values at the size they were tuned on."""
import numpy as np
import pytest
from scipy import ndimage

from ddp_lite.classical.holes import hole_rim, random_holes
from ddp_lite.core.pixel_lengths import PixelLength
from ddp_lite.method.kit.combine import mixed_with_fill, refined
from ddp_lite.method.result import DepthResult
from ddp_lite.classical.full_resolution import SMOOTHNESS_MEAN, full_size_solve, smoothness_at
from ddp_lite.method.kit.blend import fill_member_settings, rim_width, trusted_depth
from ddp_lite.method.paper.disparity import DisparityTransform


def test_a_pixel_length_holds_its_tuned_value_up_to_the_tuned_size_and_grows_with_the_short_side_above():
    reach = PixelLength(8.0, 138)
    assert reach.at((96, 128)) == 8.0 and reach.at((138, 400)) == 8.0 and reach.at((20, 20)) == 8.0
    assert reach.at((276, 346)) == pytest.approx(16.0) and reach.at((346, 276)) == pytest.approx(16.0)
    assert reach.at((207, 1000)) == pytest.approx(12.0)  # the short side: 207 / 138 = 1.5
    assert PixelLength(1.0, 138).whole((345, 500)) == 2 and PixelLength(1.0, 138).whole((352, 500)) == 3
    for bad in (dict(pixels=-1.0, tuned_short_side=138), dict(pixels=1.0, tuned_short_side=0),
                dict(pixels=True, tuned_short_side=138), dict(pixels=1.0, tuned_short_side=13.8)):
        with pytest.raises(ValueError, match="pixels|tuned_short_side"):
            PixelLength(**bad)
    with pytest.raises(ValueError, match="shape"):
        reach.at((0, 5))


def test_at_the_tuned_sizes_every_setting_is_the_pixel_value_it_was_tuned_at():
    for shape in ((48, 64), (96, 128), (115, 170), (138, 173)):  # ci, class, the eighth-size suite
        assert smoothness_at(SMOOTHNESS_MEAN, shape) == ((4.0, 4.0), (4.0, 16.0), (8.0, 4.0), (8.0, 16.0))
        assert rim_width("stereo", shape=shape) == 1 and rim_width("clean", shape=shape) == 0
        assert fill_member_settings("bilateral-solver", shape) == {"sigma_xy": 8.0}
    for shape in ((500, 741), (555, 695)):  # the photos the full-size solve was chosen on
        assert full_size_solve("clean", shape) == {"sigma_xy": 8.0}
        assert full_size_solve("stereo", shape) == {"sigma_xy": 16.0}
    # twice the eighth size: twice every length; a 12-megapixel photo: the full-size solve 5.4 times as far
    assert smoothness_at(SMOOTHNESS_MEAN, (276, 346)) == ((8.0, 4.0), (8.0, 16.0), (16.0, 4.0), (16.0, 16.0))
    assert rim_width("stereo", shape=(276, 346)) == 2 and fill_member_settings("bilateral-solver", (276, 346)) == {
        "sigma_xy": 16.0}
    assert full_size_solve("stereo", (3000, 4000))["sigma_xy"] == pytest.approx(16.0 * 3000 / 555)
    with pytest.raises(ValueError, match="source"):
        full_size_solve("kinect", (500, 741))


def test_the_stereo_rim_not_read_is_as_wide_a_share_of_the_image_at_twice_the_size():
    valid = np.ones((138, 173), bool)
    valid[40:60, 50:90] = False
    depth = np.where(valid, 2.0, np.nan).astype(np.float32)
    big = np.repeat(np.repeat(depth, 2, 0), 2, 1)  # the same holes at twice the size
    dropped, dropped_big = (np.isnan(trusted_depth(d, "stereo")) & np.isfinite(d) for d in (depth, big))
    # by hand: the 4-connected rim of a 20×40 box is 2·(20 + 40) px one step out; two steps out at twice the size
    assert dropped.sum() == 2 * (20 + 40)
    assert np.array_equal(dropped_big, hole_rim(np.isfinite(big), 2))
    assert dropped_big.sum() == pytest.approx(4 * dropped.sum(), rel=0.05)  # 4× the pixels: the same share


def _scene(H, W):
    """An analytic scene sampled at (H, W) pixel centres: a curved background and a disc in front of it, each
    its own colour → inverse depth (H, W) 1/m, colour (H, W, 3)."""
    y, x = np.meshgrid((np.arange(H) + 0.5) / H, (np.arange(W) + 0.5) / W, indexing="ij")
    inverse = 0.3 + 0.2 * x + 0.1 * y + 0.05 * np.sin(6 * x) * np.cos(5 * y)
    disc = ((x - 0.55) / 0.22) ** 2 + ((y - 0.5) / 0.3) ** 2 < 1
    inverse = np.where(disc, 0.7 + 0.1 * np.cos(3 * x + 2 * y), inverse)
    rgb = np.stack([0.4 + 0.3 * x, 0.5 + 0.2 * y, 0.5 + 0.1 * np.sin(8 * x)], -1)
    rgb = np.where(disc[..., None], np.array([0.8, 0.3, 0.2]) + 0.05 * np.cos(7 * y)[..., None], rgb)
    return inverse, rgb.astype(np.float32)


def _pooled(array):
    """2×2 block means: (2H, 2W, ...) → (H, W, ...)."""
    H, W = array.shape[0] // 2, array.shape[1] // 2
    return array.reshape(H, 2, W, 2, *array.shape[2:]).mean(axis=(1, 3))


def _twice(array):
    return np.repeat(np.repeat(array, 2, 0), 2, 1)


@pytest.mark.parametrize("source", ["stereo", "clean"])
def test_the_steps_after_the_fit_give_one_scene_the_same_answer_at_two_sizes(source):
    """The ``photo`` recipe's steps after the fit (the solves toward the fit, then a quarter of the fill) on one
    scene at the eighth size (138×173, where they were tuned) and at twice it, fed the same fit (up-sampled) and
    the same holes; the answer at twice the size, pooled back, must match the one at the eighth size. The fit
    carries texture at its own pixel grain (a net copies the image's), and a stereo matcher's rim is wrong over
    1 px of the eighth size, 2 px of twice it. With the solves' reach and the rim held in pixels, the answer at
    twice the size keeps twice as much of both: 0.14–0.19 of what the steps move, against 0.02–0.03 scaled."""
    H, W = 138, 173
    inverse_big, rgb_big = _scene(2 * H, 2 * W)
    inverse, rgb = _pooled(inverse_big), _pooled(rgb_big).astype(np.float32)
    holes = np.isnan(random_holes(np.ones((H, W), np.float32), fraction=0.2, seed=3, blob_size=min(H, W) / 16)[0])
    rim = ndimage.binary_dilation(holes) & ~holes
    wrong = np.where(rim, 1.15, 1.0)  # a matcher's rim, 15 % off
    depth = np.where(holes, np.nan, wrong / inverse).astype(np.float32)
    depth_big = np.where(_twice(holes), np.nan, _twice(wrong) / inverse_big).astype(np.float32)
    rng = np.random.default_rng(0)
    bias = 1 + 6.0 * ndimage.gaussian_filter(rng.standard_normal((H, W)), 12)  # the fit off by a smooth 10-20 %
    texture = 1 + 0.2 * ndimage.gaussian_filter(rng.standard_normal((H, W)), 1.0)  # and grainy at its own pixels
    fit = ndimage.gaussian_filter(inverse, 3.0) * bias * texture  # (H, W) 1/m: edges blurred as a fit blurs them
    rows, columns = (np.arange(2 * H) + 0.5) / 2 - 0.5, (np.arange(2 * W) + 0.5) / 2 - 0.5  # pixel centres
    fit_big = ndimage.map_coordinates(fit, np.meshgrid(rows, columns, indexing="ij"), order=1, mode="nearest")
    transform = DisparityTransform.from_depth(1.0 / inverse_big)

    def answer(fit_inverse, depth_in, image):
        disparity = np.asarray(transform.to_disparity((1.0 / fit_inverse).astype(np.float32)), np.float32)
        result = DepthResult(depth=transform.to_depth(disparity).astype(np.float32), disparity=disparity, rgb=None,
                             history={}, transform=transform, iterations=0, best_iteration=0, seconds=0.0)
        given = depth_in.copy()
        out = mixed_with_fill(refined(result, depth_in, image, source), depth_in, image, 0.25, source)
        assert np.array_equal(depth_in, given, equal_nan=True)  # the caller's input untouched
        return 1.0 / out.depth.astype(np.float64)  # (H, W) 1/m

    small, big = answer(fit, depth, rgb), answer(fit_big, depth_big, rgb_big)
    # scored: the holes away from the disc's edge, where pooling mixes two surfaces that no answer at the small
    # size can hold
    edge = ndimage.binary_dilation(np.hypot(*np.gradient(inverse)) > 0.02, iterations=2)
    scored = holes & ~edge
    assert scored.sum() > 0.15 * holes.size
    rms = lambda x: float(np.sqrt(np.mean(x[scored] ** 2)))  # noqa: E731
    moved = rms(small - fit)  # how far the steps took the answer from the fit
    assert moved > 0.03
    assert rms(_pooled(big) - small) < 0.05 * moved
