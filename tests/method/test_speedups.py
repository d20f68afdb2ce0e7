"""Coarse-to-fine fitting: shapes, holes, the downsampling helpers, argument checks, determinism."""
import numpy as np
import pytest

from ddp_lite.core.camera import Camera, look_at
from ddp_lite.method.config import FitConfig
from ddp_lite.method.coarse_to_fine import (_downsample_camera, _downsample_depth, _downsample_image,
                                     complete_depth_coarse_to_fine)
from conftest import TINY, tilted_plane


def plane_case(height=24, width=32):
    gt = tilted_plane(height, width)
    depth = gt.copy()
    depth[8:16, 10:20] = np.nan
    rgb = np.random.default_rng(0).random((height, width, 3)).astype(np.float32)
    return rgb, depth, gt


def test_downsample_depth_keeps_holes_and_takes_the_nearest_surface():
    nan = np.nan
    depth = np.array([[1.0, 2.0, 5.0, 5.0, 7.0],
                      [3.0, 4.0, nan, 6.0, 8.0],
                      [2.0, 2.0, 9.0, 9.0, nan]], np.float32)
    small = _downsample_depth(depth, 2)
    assert small.shape == (2, 3)
    assert small[0, 0] == 1.0  # min of the block, not the mean 2.5
    assert np.isnan(small[0, 1])  # one hole in the block → hole
    assert np.isnan(small[0, 2])  # the padded column counts as unknown
    assert np.isnan(small[1]).all()  # the padded row too
    assert np.isnan(_downsample_depth(np.full((4, 4), np.nan, np.float32), 2)).all()


def test_downsample_image_averages_and_camera_shrinks():
    image = np.arange(4 * 6 * 3, dtype=np.float32).reshape(4, 6, 3) / 100
    small = _downsample_image(image, 2)
    assert small.shape == (2, 3, 3)
    assert np.allclose(small[0, 0], image[:2, :2].mean(axis=(0, 1)))
    camera = Camera.from_fov(64, 48, 60.0)
    coarse = _downsample_camera(camera, 2)
    assert (coarse.width, coarse.height) == (32, 24)
    assert coarse.focal == pytest.approx(camera.focal / 2)


def test_coarse_to_fine_fills_holes_with_finite_depth():
    rgb, depth, gt = plane_case()
    config = FitConfig(iterations=12, eval_every=3, **TINY)
    result = complete_depth_coarse_to_fine(rgb, depth, variant="rgbd", config=config, gt_depth=gt)
    assert result.depth.shape == depth.shape and np.all(np.isfinite(result.depth))
    assert result.rgb.shape == rgb.shape
    assert result.iterations == 12 and list(result.history["stage_iterations"]) == [6, 6]
    assert len(result.history["loss"]) == 12
    assert list(result.history["eval_iteration"]) == [3, 6, 9, 12]
    assert list(result.history["eval_scale"]) == [2, 2, 1, 1]
    assert result.seconds == pytest.approx(result.history["stage_seconds"].sum())


def test_coarse_to_fine_with_warp_and_odd_size():
    rgb, depth, _ = plane_case(23, 31)
    ref = Camera.from_fov(31, 23, 60.0)
    nbr = Camera(ref.K, look_at([0.1, 0, 0], [0.1, 0, 3.0]), 31, 23)
    config = FitConfig(iterations=6, **TINY)
    result = complete_depth_coarse_to_fine(rgb, depth, ref, [(rgb, nbr)], config=config, coarse_fraction=0.5)
    assert result.depth.shape == (23, 31) and np.all(np.isfinite(result.depth))


@pytest.mark.parametrize("scale", [1, 0, 2.5, True, "2"])
def test_bad_scale_raises(scale):
    rgb, depth, _ = plane_case()
    with pytest.raises(ValueError, match="scale"):
        complete_depth_coarse_to_fine(rgb, depth, variant="rgbd", config=FitConfig(iterations=4, **TINY), scale=scale)


@pytest.mark.parametrize("fraction", [0.0, 1.0, -0.2])
def test_bad_coarse_fraction_raises(fraction):
    rgb, depth, _ = plane_case()
    with pytest.raises(ValueError, match="coarse_fraction"):
        complete_depth_coarse_to_fine(rgb, depth, variant="rgbd", config=FitConfig(iterations=4, **TINY),
                                      coarse_fraction=fraction)


def test_coarse_to_fine_is_deterministic():
    rgb, depth, _ = plane_case()
    config = FitConfig(iterations=8, auto_stop=True, patience=50, eval_every=2, **TINY)
    a = complete_depth_coarse_to_fine(rgb, depth, variant="rgbd", config=config)
    b = complete_depth_coarse_to_fine(rgb, depth, variant="rgbd", config=config)
    assert np.array_equal(a.depth, b.depth)
    assert np.array_equal(a.history["loss"], b.history["loss"])
