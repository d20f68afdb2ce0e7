"""The NYU toolbox's cross-bilateral fill: one pass (OpenCV's joint bilateral filter, normalised by the usable
pixels) against a per-pixel double loop, against a normalised Gaussian convolution (constant guide) and
against the kit's former NumPy pass on a real photograph; the multi-scale fill on an edge and a big hole."""
import numpy as np
import pytest
from scipy import ndimage

from ddp_lite.classical.baselines import fill
from ddp_lite.classical.guided_fills import fill_cross_bilateral, joint_bilateral_fill


def _brute_force(depth, guide, sigma_s, sigma_r, radius):
    """The joint bilateral mean over the disc of ``radius`` px written out pixel by pixel (NaN = unusable /
    nothing in the window)."""
    H, W = depth.shape
    out, weight = np.full((H, W), np.nan), np.zeros((H, W))
    for y in range(H):
        for x in range(W):
            num = den = 0.0
            for yy in range(max(0, y - radius), min(H, y + radius + 1)):
                for xx in range(max(0, x - radius), min(W, x + radius + 1)):
                    if np.isnan(depth[yy, xx]) or (yy - y) ** 2 + (xx - x) ** 2 > radius ** 2:
                        continue
                    w = np.exp(-((yy - y) ** 2 + (xx - x) ** 2) / (2 * sigma_s ** 2)) * \
                        np.exp(-(guide[yy, xx] - guide[y, x]) ** 2 / (2 * sigma_r ** 2))
                    num += w * depth[yy, xx]
                    den += w
            if den > 0:
                out[y, x] = num / den
            weight[y, x] = den
    return out, weight


def test_one_pass_matches_the_double_loop():
    rng = np.random.default_rng(0)
    depth = rng.uniform(1.0, 3.0, (9, 11))
    depth[rng.random(depth.shape) < 0.4] = np.nan
    depth[0:4, 0:4] = np.nan  # with radius 1, pixel (0, 0) sees no usable depth: NaN in both
    guide = rng.random((9, 11))
    for sigma_s, sigma_r, radius in ((2.0, 0.1, 2), (1.0, 0.5, 1), (3.0, 0.05, 3)):
        expected, weight = _brute_force(depth, guide, sigma_s, sigma_r, radius)
        got = joint_bilateral_fill(depth, guide, sigma_s, sigma_r, radius)
        # weights summing below 1e-6 count as unreached (NaN); float32 inside OpenCV, on 1–3 m
        np.testing.assert_allclose(got[weight > 2e-6], expected[weight > 2e-6], rtol=0, atol=2e-6)
        assert np.isnan(got[weight < 0.5e-6]).all()
        assert (weight > 2e-6).mean() > 0.6 and (weight == 0).any()


def test_constant_guide_is_a_normalised_gaussian_convolution():
    rng = np.random.default_rng(1)
    depth = rng.uniform(1.0, 3.0, (20, 24))
    depth[rng.random(depth.shape) < 0.5] = np.nan
    valid = np.isfinite(depth)
    radius, sigma_s = 4, 2.5
    offsets = np.arange(-radius, radius + 1)
    r2 = offsets[:, None] ** 2 + offsets[None, :] ** 2
    kernel = np.where(r2 <= radius ** 2, np.exp(-r2 / (2 * sigma_s ** 2)), 0.0)  # OpenCV's window is a disc
    num = ndimage.correlate(np.where(valid, depth, 0.0), kernel, mode="constant")
    den = ndimage.correlate(valid.astype(float), kernel, mode="constant")
    got = joint_bilateral_fill(depth, np.full(depth.shape, 0.3), sigma_s, 0.01, radius)
    np.testing.assert_allclose(got, num / den, rtol=0, atol=2e-6)


def _two_regions(H=48, W=64):
    """Depth 1 m left of column 30 and 3 m right of it, the guide dark / bright likewise, a hole across it."""
    depth = np.where(np.arange(W)[None, :] < 30, 1.0, 3.0).repeat(H, 0)
    rgb = np.where(np.arange(W)[None, :, None] < 30, 0.2, 0.8).repeat(H, 0).repeat(3, 2).astype(np.float32)
    holes = np.zeros((H, W), bool)
    holes[15:30, 22:38] = True
    return np.where(holes, np.nan, depth), depth, rgb, holes


def test_the_fill_follows_the_colour_edge():
    depth, gt, rgb, holes = _two_regions()
    out = fill_cross_bilateral(depth, rgb)
    error = np.abs(out - gt)[holes]
    # each side keeps nearer its own colour's depth than the other's; the finest scale's wide range
    # sigma (0.2 against a contrast of 0.6) lets a little of the other side in (measured max 0.24 m)
    assert error.max() < 0.5 and error.mean() < 0.1
    left = np.arange(depth.shape[1])[None, :] < 30
    assert np.all(out[holes & left] < 2.0) and np.all(out[holes & ~left] > 2.0)
    np.testing.assert_array_equal(out[~holes], depth[~holes])


def test_a_hole_larger_than_every_window_is_filled_from_the_coarse_scales():
    H, W = 64, 64
    v, u = np.mgrid[0:H, 0:W]
    gt = 2.0 + 0.01 * u
    depth = np.where((abs(u - 32) < 14) & (abs(v - 32) < 14), np.nan, gt)  # 27 px across: > 11 px windows
    rgb = np.full((H, W, 3), 0.5, np.float32)
    single = fill_cross_bilateral(depth, rgb, space_sigmas=(12.0,), range_sigmas=(0.2,))
    multi = fill_cross_bilateral(depth, rgb)
    assert np.all(np.isfinite(multi))
    centre = np.s_[28:37, 28:37]
    # one scale cannot reach the centre (nearest fallback); three scales do, with a blend of the rim
    assert np.abs(multi - gt)[centre].max() < 0.15
    assert np.abs(multi - gt)[centre].mean() < np.abs(single - gt)[centre].mean() + 1e-9
    assert fill(depth, rgb, method="cross-bilateral").tobytes() == multi.tobytes()


def test_bad_inputs():
    depth, _, rgb, _ = _two_regions()
    with pytest.raises(ValueError, match="rgb"):
        fill_cross_bilateral(depth)
    with pytest.raises(ValueError, match="same length"):
        fill_cross_bilateral(depth, rgb, space_sigmas=(1.0, 2.0), range_sigmas=(0.1,))
    with pytest.raises(ValueError, match="positive"):
        fill_cross_bilateral(depth, rgb, space_sigmas=(0.0,), range_sigmas=(0.1,))
    with pytest.raises(ValueError, match="radius"):
        fill_cross_bilateral(depth, rgb, radius=0)
