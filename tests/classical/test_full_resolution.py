"""The full-resolution refinement (``ddp_lite.classical.full_resolution``): valid pixels kept exactly, a blurred
target sharpened at a depth edge that is also a colour edge (judged against the analytic truth), inputs
untouched, bad arguments refused. No DDP fit: the target is made here."""
import numpy as np
import pytest
from scipy import ndimage

from ddp_lite.classical.full_resolution import REFINEMENTS, refine_full_resolution

H, W, EDGE = 60, 80, 40  # two fronto-parallel planes meeting at column EDGE


def two_planes():
    """(rgb, depth with a hole across the edge, truth, blurred target): near plane left, far plane right,
    the colour edge on the depth edge, a little texture on both."""
    rng = np.random.default_rng(0)
    truth = np.where(np.arange(W)[None, :] < EDGE, 1.0, 2.0) * np.ones((H, 1))  # metres
    rgb = np.where(np.arange(W)[None, :, None] < EDGE, 0.25, 0.75) * np.ones((H, 1, 3))
    rgb = np.clip(rgb + rng.uniform(-0.02, 0.02, rgb.shape), 0, 1).astype(np.float32)
    depth = truth.astype(np.float32).copy()
    depth[15:45, 22:58] = np.nan  # the hole spans the edge
    # the working-size fit up-sampled: the right disparity, blurred across the edge (as ×6 up-sampling does)
    target = 1.0 / ndimage.gaussian_filter(1.0 / truth, sigma=5.0, mode="nearest")
    return rgb, depth, truth, target


def hole_rmse(depth, filled, truth):
    holes = np.isnan(depth)
    return float(np.sqrt(np.mean((1.0 / filled[holes] - 1.0 / truth[holes]) ** 2)))


@pytest.mark.parametrize("method", REFINEMENTS)
def test_valid_pixels_kept_exactly_and_inputs_untouched(method):
    rgb, depth, truth, target = two_planes()
    depth[3, 5] = 1.2345678  # an odd value, to see it survive bit for bit
    copies = [a.copy() for a in (rgb, depth, target)]
    out = refine_full_resolution(depth, rgb, target, method=method)
    valid = np.isfinite(depth)
    assert out.dtype == np.float32 and out.shape == depth.shape and np.all(np.isfinite(out))
    assert np.array_equal(out[valid], depth[valid])
    for before, after in zip(copies, (rgb, depth, target)):
        assert np.array_equal(before, after, equal_nan=True)


@pytest.mark.parametrize("residual", [True, False])
@pytest.mark.parametrize("method", REFINEMENTS)
def test_blurred_target_sharpened_at_the_edge(method, residual):
    rgb, depth, truth, target = two_planes()
    before = hole_rmse(depth, np.where(np.isnan(depth), target, depth), truth)
    after = hole_rmse(depth, refine_full_resolution(depth, rgb, target, method=method, residual=residual), truth)
    assert after < 0.5 * before, (method, before, after)
    band = np.isnan(depth) & (np.abs(np.arange(W)[None, :] - EDGE + 0.5) < 4)  # the edge's own pixels
    err_before = np.abs(1 / target[band] - 1 / truth[band]).mean()
    refined = refine_full_resolution(depth, rgb, target, method=method, residual=residual)
    assert np.abs(1 / refined[band] - 1 / truth[band]).mean() < 0.5 * err_before


@pytest.mark.parametrize("method", REFINEMENTS)
def test_residual_removes_a_fit_biased_like_its_rim(method):
    """A fit off by a constant disparity everywhere (known on the valid pixels): the residual step carries
    that offset into the hole, so the fill lands on the truth; without it the fill keeps part of the bias."""
    rgb, depth, truth, _ = two_planes()
    biased = 1.0 / (1.0 / truth + 0.1)
    with_residual = hole_rmse(depth, refine_full_resolution(depth, rgb, biased, method=method), truth)
    without = hole_rmse(depth, refine_full_resolution(depth, rgb, biased, method=method, residual=False), truth)
    assert with_residual < 0.2 * 0.1 and with_residual < 0.5 * without, (with_residual, without)


def test_zero_and_negative_depth_are_holes():
    rgb, depth, truth, target = two_planes()
    zeroed = np.where(np.isnan(depth), 0.0, depth).astype(np.float32)
    assert np.array_equal(refine_full_resolution(zeroed, rgb, target), refine_full_resolution(depth, rgb, target))


def test_no_holes_returns_the_input():
    rgb, _, truth, target = two_planes()
    assert np.array_equal(refine_full_resolution(truth, rgb, target), truth.astype(np.float32))


@pytest.mark.parametrize("kwargs, message", [
    (dict(method="median"), "method must be one of"),
    (dict(hole_confidence=0.0), "hole_confidence must be a positive number"),
    (dict(hole_confidence=1.5), r"hole_confidence must be in \(0, 1\]"),
    (dict(hole_confidence=float("nan")), "hole_confidence"),
    (dict(lam=-1.0), "lam must be a positive number"),
    (dict(method="fgs", radius=3), "method 'fgs' takes"),
    (dict(method="guided-filter", radius=2.5), "radius must be a positive integer"),
])
def test_bad_settings_refused(kwargs, message):
    rgb, depth, _, target = two_planes()
    with pytest.raises(ValueError, match=message):
        refine_full_resolution(depth, rgb, target, **kwargs)


def test_bad_arrays_refused():
    rgb, depth, _, target = two_planes()
    with pytest.raises(ValueError, match="target must be a numeric"):
        refine_full_resolution(depth, rgb, target[:, :-1])
    nan_target = target.copy()
    nan_target[30, 40] = np.nan  # inside the hole
    with pytest.raises(ValueError, match="target must be finite and > 0"):
        refine_full_resolution(depth, rgb, nan_target)
    outside = target.copy()
    outside[2, 2] = np.nan  # a valid pixel: read by the residual step only
    with pytest.raises(ValueError, match="every pixel"):
        refine_full_resolution(depth, rgb, outside)
    assert np.isfinite(refine_full_resolution(depth, rgb, outside, residual=False)).all()
    with pytest.raises(ValueError, match="rgb"):
        refine_full_resolution(depth, rgb[:, :-1], target)
    with pytest.raises(ValueError, match="rgb"):
        refine_full_resolution(depth, None, target)
    with pytest.raises(ValueError, match="depth"):
        refine_full_resolution(np.full((H, W), np.nan), rgb, target)


def test_the_mean_over_smoothness_is_the_disparity_mean_of_the_solves_and_keeps_the_input():
    from ddp_lite.classical.full_resolution import SMOOTHNESS_MEAN, refine_over_smoothness
    rgb, depth, truth, target = two_planes()
    depth[3, 5] = 1.2345678
    before = depth.copy()
    out = refine_over_smoothness(depth, rgb, target)
    assert np.array_equal(depth, before, equal_nan=True)  # the caller's array untouched
    valid = ~np.isnan(depth)
    assert np.array_equal(out[valid], depth[valid])  # bit for bit
    solves = [refine_full_resolution(depth, rgb, target, sigma_xy=s, lam=lam) for s, lam in SMOOTHNESS_MEAN]
    expected = 1.0 / np.mean([1.0 / x.astype(np.float64) for x in solves], axis=0)  # the mean in disparity
    assert np.allclose(out[~valid], expected[~valid], rtol=1e-6)
    assert len({float(x[~valid].mean()) for x in solves}) == len(SMOOTHNESS_MEAN)  # four different solves
    assert hole_rmse(depth, out, truth) < 0.5 * hole_rmse(depth, np.where(valid, depth, target), truth)


def test_the_mean_over_smoothness_of_one_plane_is_that_plane():
    from ddp_lite.classical.full_resolution import refine_over_smoothness
    depth = np.full((40, 60), 2.5, np.float32)  # a fronto-parallel plane; the fit knows it too
    depth[10:30, 20:40] = np.nan
    rgb = np.random.default_rng(1).random((40, 60, 3)).astype(np.float32)
    out = refine_over_smoothness(depth, rgb, np.full((40, 60), 2.5))
    assert np.allclose(out, 2.5, rtol=1e-5)


@pytest.mark.parametrize("settings, match", [([], "settings"), ("abc", "settings"), ([(4.0,)], "settings"),
                                             ([(4.0, 0.0)], "lam"), ([(-1.0, 4.0)], "sigma_xy")])
def test_the_mean_over_smoothness_refuses_bad_settings(settings, match):
    from ddp_lite.classical.full_resolution import refine_over_smoothness
    rgb, depth, _, target = two_planes()
    with pytest.raises(ValueError, match=match):
        refine_over_smoothness(depth, rgb, target, settings=settings)
