"""Hole and noise models: real SGM holes where texture is missing, accurate SGM depth elsewhere,
and seeded synthetic holes that leave their input alone, each checked against the ground truth."""
import numpy as np
import pytest
from scipy import ndimage

from ddp_lite.classical.holes import edge_band_holes, kinect_noise, random_holes
from ddp_lite.world.scenes import make_scene
from ddp_lite.classical.stereo import (disparity_to_depth, gt_disparity, pixel_disparity, sgm_depth, sgm_depth_subsampled,
                             sgm_disparity)


@pytest.fixture(scope="module")
def house():
    return make_scene("house", size=(96, 128), n_views=1, seed=0)


def _step_depth(H=40, W=60, near=1.5, far=4.0):
    depth = np.full((H, W), far, np.float32)
    depth[10:30, 15:35] = near
    return depth


def test_sgm_holes_fall_in_textureless_regions_and_depth_is_accurate_elsewhere(house):
    before = house[0].rgb.copy(), house.right[0].rgb.copy()
    gt, labels = house[0].depth, house.labels[0]
    flat = labels <= 1  # sky and plain paint
    for params in ("dense", "sparse"):
        depth, mask = sgm_depth(house, 0, params)
        assert depth.dtype == np.float32 and depth.shape == gt.shape
        np.testing.assert_array_equal(mask, np.isfinite(depth))
        holes = ~mask
        assert holes[flat].mean() > 3 * holes[~flat].mean()  # missing texture → missing depth
        assert holes[flat].sum() > 0.5 * holes.sum()  # most holes are in the textureless parts
        rel = np.abs(depth - gt) / gt
        assert np.median(rel[mask & ~flat]) < 0.04  # within a few percent where there is texture
    dense, sparse = (1 - sgm_depth(house, 0, p)[1].mean() for p in ("dense", "sparse"))
    assert 0.05 < dense < sparse < 0.8
    np.testing.assert_array_equal(house[0].rgb, before[0])  # the scene is left alone
    np.testing.assert_array_equal(house.right[0].rgb, before[1])


def test_sgm_disparity_and_depth_agree_and_d1_is_small(house):
    disparity, mask = sgm_disparity(house, 0)
    depth, mask2 = sgm_depth(house, 0)
    np.testing.assert_array_equal(mask, mask2)
    fb = house[0].camera.K[0, 0] * house.meta["baseline"]
    np.testing.assert_allclose(depth[mask] * disparity[mask], fb, rtol=1e-5)
    truth = gt_disparity(house, 0)
    np.testing.assert_allclose(truth, fb / house[0].depth, rtol=1e-6)
    error = np.abs(disparity - truth)[mask & (house.labels[0] >= 2)]
    assert np.mean((error > 3) & (error > 0.05 * truth[mask & (house.labels[0] >= 2)])) < 0.05  # KITTI D1
    assert np.median(error) < 0.3  # px


def test_sgm_is_deterministic_and_rejects_bad_input(house):
    a, _ = sgm_depth(house, 0, "sparse")
    b, _ = sgm_depth(house, 0, "sparse")
    np.testing.assert_array_equal(a, b)
    with pytest.raises(ValueError, match="params"):
        sgm_depth(house, 0, "medium")
    with pytest.raises(ValueError, match="ref"):
        sgm_depth(house, 5)


def test_random_holes_cover_the_fraction_in_seeded_blobs():
    depth = np.linspace(1.0, 5.0, 48 * 64, dtype=np.float32).reshape(48, 64)
    depth[0, 0] = np.nan  # an existing hole stays a hole
    before = depth.copy()
    out, mask = random_holes(depth, fraction=0.2, seed=1)
    np.testing.assert_array_equal(depth, before)
    assert out.dtype == np.float32 and np.isnan(out[0, 0])
    assert abs((~mask).mean() - 0.2) < 0.01
    np.testing.assert_array_equal(out[mask], depth[mask])
    _, n_blobs = ndimage.label(~mask)
    assert n_blobs < 30  # blobs, not salt-and-pepper (that would be ~600 components)
    again, _ = random_holes(depth, fraction=0.2, seed=1)
    other, _ = random_holes(depth, fraction=0.2, seed=2)
    np.testing.assert_array_equal(np.isnan(again), ~mask)
    assert (np.isnan(other) != ~mask).mean() > 0.1


def test_edge_band_holes_straddle_a_depth_edge():
    depth = _step_depth()
    before = depth.copy()
    out, mask = edge_band_holes(depth, width=4, seed=0)
    np.testing.assert_array_equal(depth, before)
    removed = depth[~mask]
    assert removed.size > 0 and removed.min() == 1.5 and removed.max() == 4.0  # both sides of the edge
    edge = np.zeros(depth.shape, bool)
    edge[:, 1:] |= depth[:, 1:] != depth[:, :-1]
    edge[:, :-1] |= depth[:, 1:] != depth[:, :-1]
    edge[1:] |= depth[1:] != depth[:-1]
    edge[:-1] |= depth[1:] != depth[:-1]
    distance = ndimage.distance_transform_edt(~edge)
    assert distance[~mask].max() <= 2.0 + 1e-9  # within width / 2 of the edge
    assert (~mask).sum() < 0.5 * edge.sum() * 4 + 1  # only part of the edge
    a, _ = edge_band_holes(depth, width=4, seed=0)
    b, _ = edge_band_holes(depth, width=4, seed=5)
    np.testing.assert_array_equal(np.isnan(a), ~mask)
    assert not np.array_equal(np.isnan(a), np.isnan(b))
    with pytest.raises(ValueError, match="depth"):
        edge_band_holes(np.full((20, 20), 2.0, np.float32))


def test_kinect_noise_grows_as_z_squared_and_is_quantised():
    sigma = 1.5e-3
    stds = {}
    for z in (1.0, 3.0):
        depth = np.full((80, 80), z, np.float32)
        out, mask = kinect_noise(depth, seed=0, sigma_coef=sigma, edge_dropout=0.0)
        assert mask.all()
        fb = 580.0 * 0.075
        steps = fb / out.astype(np.float64) * 8  # disparity in 1/8 px must be an integer
        np.testing.assert_allclose(steps, np.round(steps), atol=1e-3)
        stds[z] = out.std()
        quantisation = z ** 2 / (fb * 8) / np.sqrt(12)  # uniform rounding in depth
        expected = np.hypot(sigma * z ** 2, quantisation)
        assert 0.7 * expected < stds[z] < 1.3 * expected
    assert 5 < stds[3.0] / stds[1.0] < 10
    _, mask = kinect_noise(np.full((10, 10), 12.0, np.float32))
    assert not mask.any()  # out of range


def test_kinect_noise_drops_the_far_side_of_edges_only():
    depth = _step_depth()
    before = depth.copy()
    out, mask = kinect_noise(depth, seed=3, edge_dropout=1.0, edge_width=2)
    np.testing.assert_array_equal(depth, before)
    assert np.all(depth[~mask] == 4.0)  # the background next to the object
    near_object = ndimage.binary_dilation(depth == 1.5, np.ones((5, 5), bool)) & (depth == 4.0)  # 2 px, square
    np.testing.assert_array_equal(~mask, near_object)
    a, _ = kinect_noise(depth, seed=3, edge_dropout=0.5)
    b, _ = kinect_noise(depth, seed=3, edge_dropout=0.5)
    np.testing.assert_array_equal(a, b)


@pytest.mark.parametrize("call, word", [
    (lambda d: random_holes(d, fraction=1.5), "fraction"),
    (lambda d: random_holes(d[None]), "depth"),
    (lambda d: random_holes(d, seed=-1), "seed"),
    (lambda d: random_holes(np.where(d > 2, np.inf, d)), "depth"),
    (lambda d: edge_band_holes(d, width=0), "width"),
    (lambda d: kinect_noise(d, subpixel=0), "subpixel"),
    (lambda d: kinect_noise(d, depth_range=(3, 1)), "depth_range"),
])
def test_hole_models_reject_bad_input(call, word):
    with pytest.raises(ValueError, match=word):
        call(_step_depth())


def test_hole_models_refuse_a_non_float_depth_with_a_type_error():  # the one depth contract: checks.check_depth
    with pytest.raises(TypeError, match="depth"):
        random_holes(_step_depth().astype(int))


def test_pixel_disparity_and_depth_are_inverse_and_sgm_subsampling_keeps_block_centres():
    depth = np.array([[1.0, 2.0], [np.nan, 4.0]], np.float32)
    disparity = pixel_disparity(depth, 100.0, 0.5, doffs=2.0)  # f·B/z − doffs
    np.testing.assert_allclose(disparity, [[48.0, 23.0], [np.nan, 10.5]])
    np.testing.assert_allclose(disparity_to_depth(disparity, 100.0, 0.5, doffs=2.0), depth, rtol=1e-6)
    scene = make_scene("desk", size=(48, 60), n_views=1)
    full, _ = sgm_depth(scene, 0)
    np.testing.assert_array_equal(sgm_depth_subsampled(scene, 0, 3), full[1::3, 1::3])
    with pytest.raises(ValueError, match="scale"):
        sgm_depth_subsampled(scene, 0, 2)
