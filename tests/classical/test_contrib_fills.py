"""The fills built on OpenCV's contrib modules (cv2.ximgproc, cv2.xphoto) against independent references on a
real photograph (Motorcycle, pooled to 125×185, blob holes) and on cases with a known answer."""
import cv2
import numpy as np
import pytest

from fill_references import numpy_joint_bilateral
from ddp_lite.classical.depth_fills import fill_ebi, fill_fbf, fill_linear, fill_nearest
from ddp_lite.classical.guided_fills import masked_guided_filter, fill_fast_global_smoother, joint_bilateral_fill
from ddp_lite.studies.real_cases import make_real_case


@pytest.fixture(scope="module")
def photo():
    """(disparity (H, W) px with NaN holes, true disparity with NaN where unknown, rgb, scored holes)."""
    case = make_real_case("blobs-1", factor=4)
    return case.fb / case.depth, case.fb / case.gt, case.rgb, case.scored_holes


def _rmse(filled, truth, scored):
    return float(np.sqrt(np.mean((filled[scored] - truth[scored]) ** 2)))


@pytest.mark.parametrize("sigma_s, sigma_r", [(12.0, 0.2), (5.0, 0.08), (8.0, 0.02)])  # the fill's three scales
def test_opencv_joint_bilateral_matches_the_float64_numpy_pass_on_a_photo(photo, sigma_s, sigma_r):
    disparity, _, rgb, _ = photo
    grey = rgb.astype(np.float64) @ np.array([0.2989, 0.5870, 0.1140])
    expected, weight = numpy_joint_bilateral(disparity, grey, sigma_s, sigma_r, 5, disc=True)
    got = joint_bilateral_fill(disparity, grey, sigma_s, sigma_r, 5)
    # OpenCV tabulates the range kernel in float32: far in its tail its weight sums run up to ~40× low, so
    # near the 1e-6 cut-off the two may disagree on whether a pixel is reached, not beyond 1e-4
    assert np.isfinite(got[weight > 1e-4]).all() and np.isnan(got[weight < 0.5e-6]).all()
    both = np.isfinite(got) & (weight > 2e-6)
    assert both.mean() > 0.85  # 20 % of the pixels are blob holes, some beyond the 5 px disc
    # disparities 20–45 px; measured at most 2.9e-4 px (σ_r = 0.02), 4.5e-6 px at σ_r = 0.2
    assert np.max(np.abs(got - expected)[both]) < 2e-3


def test_our_guided_filter_with_all_weights_one_is_opencvs(photo):
    # the library filter is the independent reference for the kit's weighted one when nothing is masked;
    # a [0, 1] colour guide loses OpenCV's digits at small eps (1.1 px rms at eps 1e-4), ×255 keeps them
    _, truth, rgb, _ = photo
    known = np.isfinite(truth)
    target = fill_nearest(np.where(known, truth, np.nan)).astype(np.float64)
    for radius, eps in ((2, 1e-4), (4, 1e-3)):
        ours, _ = masked_guided_filter(rgb.astype(np.float64), target, np.ones_like(target), radius, eps)
        library = cv2.ximgproc.guidedFilter((rgb * 255).astype(np.float32), target.astype(np.float32), radius,
                                            eps * 255 ** 2)
        assert np.max(np.abs(ours - library)) < 0.05  # measured 0.013 px at eps 1e-4 (float32 in OpenCV)


def test_opencvs_guided_filter_normalised_by_the_mask_is_not_the_masked_fit(photo):
    # why the guided-filter fill keeps its own weighted regression: guidedFilter(valid·d) / guidedFilter(valid)
    # divides two affine models of the colour, and where few pixels are valid the denominator goes to 0
    disparity, truth, rgb, scored = photo
    valid = np.isfinite(disparity)
    guide = (rgb * 255).astype(np.float32)
    ours, reach = masked_guided_filter(rgb.astype(np.float64), np.where(valid, disparity, 0.0),
                                        valid.astype(np.float64), 2, 1e-4)
    num = cv2.ximgproc.guidedFilter(guide, np.where(valid, disparity, 0.0).astype(np.float32), 2, 1e-4 * 255 ** 2)
    den = cv2.ximgproc.guidedFilter(guide, valid.astype(np.float32), 2, 1e-4 * 255 ** 2)
    reached = scored & (reach > 1e-9) & (np.abs(den) > 1e-6)
    assert _rmse(num / np.where(reached, den, 1.0), truth, reached) > 2 * _rmse(ours, truth, reached)


def _edge_case(H=40, W=60):
    """Depth 1 m left of column 30, 3 m right, the colour dark / bright likewise, a hole across the edge."""
    left = np.arange(W)[None, :] < 30
    depth = np.where(left, 1.0, 3.0).repeat(H, 0)
    rgb = np.where(left[..., None], 0.2, 0.8).repeat(H, 0).repeat(3, 2).astype(np.float32)
    holes = np.zeros((H, W), bool)
    holes[12:28, 20:40] = True
    return np.where(holes, np.nan, depth), depth, rgb, holes


def test_the_fast_global_smoother_keeps_a_constant_and_stops_at_a_colour_edge():
    depth, truth, rgb, holes = _edge_case()
    constant = np.where(holes, np.nan, 2.5)
    np.testing.assert_allclose(fill_fast_global_smoother(constant, rgb), 2.5, atol=1e-5)
    out = fill_fast_global_smoother(depth, rgb)
    assert np.max(np.abs(out - truth)[holes]) < 0.05  # a 2 m step, filled to 2.5 % of it


def test_the_fast_global_smoother_beats_nearest_on_the_photo(photo):
    disparity, truth, rgb, scored = photo
    assert _rmse(fill_fast_global_smoother(disparity, rgb), truth, scored) < _rmse(fill_nearest(disparity), truth, scored)


def test_shift_map_copies_valid_depth_into_the_holes(photo):
    # an exemplar method pastes valid pixels: every filled value is one of the input's valid values. A property
    # of each pixel, so a 64×96 window of the photo (30 % holes) shows it: shift-map's graph cuts over every
    # offset take ~5× longer on the whole 125×185
    disparity = photo[0][30:94, 40:136]
    valid = np.isfinite(disparity)
    assert 0.2 < (~valid).mean() < 0.4
    out = fill_ebi(disparity)
    known = np.unique(disparity[valid].astype(np.float64))
    filled = out[~valid].astype(np.float64)
    at = np.clip(np.searchsorted(known, filled), 1, len(known) - 1)
    gap = np.minimum(np.abs(filled - known[at - 1]), np.abs(filled - known[at]))
    assert np.max(gap) < 1e-4 * np.max(known)  # float32 round trip about the mean


def test_the_fourier_fill_reproduces_a_smooth_surface_to_its_quantisation():
    v, u = np.mgrid[0:64, 0:64]
    truth = 2.0 + 0.3 * np.sin(u / 20.0) + 0.2 * np.cos(v / 25.0)
    holes = (u - 30) ** 2 + (v - 34) ** 2 < 8 ** 2
    out = fill_fbf(np.where(holes, np.nan, truth))
    level = np.ptp(truth[~holes]) / 63
    assert np.max(np.abs(out - truth)[holes]) < 4 * level  # measured 2.5 levels (1/63 of the range each)
    np.testing.assert_array_equal(out[~holes], truth[~holes].astype(np.float32))


@pytest.mark.parametrize("method", ["ebi", "fbf", "fast-global-smoother"])
def test_the_new_fills_refuse_bad_input_and_survive_sparse_depth(method):
    from ddp_lite.classical.baselines import fill
    rgb = np.full((20, 30, 3), 0.5, np.float32)
    with pytest.raises(ValueError, match="at least 1 valid"):
        fill(np.full((20, 30), np.nan), rgb, method=method)
    with pytest.raises(ValueError, match="inf"):
        fill(np.full((20, 30), np.inf), rgb, method=method)
    with pytest.raises(ValueError, match=r"rgb must be \(H, W, 3\)"):
        fill(np.ones((20, 30)), np.zeros((20, 31, 3)), method=method)
    one = np.full((20, 30), np.nan)
    one[4, 7] = 2.0  # a single valid pixel: every hole takes its depth
    np.testing.assert_allclose(fill(one, rgb, method=method), 2.0, atol=1e-5)


def test_the_fast_global_smoother_needs_the_image_and_positive_parameters():
    depth, _, rgb, _ = _edge_case()
    with pytest.raises(ValueError, match="rgb is required"):
        fill_fast_global_smoother(depth)
    for bad in ({"lam": 0.0}, {"sigma_color": -1.0}, {"lam": np.nan}, {"lam": True}):
        with pytest.raises(ValueError, match="must be a positive number"):
            fill_fast_global_smoother(depth, rgb, **bad)
