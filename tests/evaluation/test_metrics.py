"""Metrics against cases small enough to compute by hand (and PSNR against scikit-image)."""
# open3d is imported inside the tests that use it: loading it takes ~3 s, which every test worker paid at collection
import numpy as np
import pytest
from skimage.metrics import peak_signal_noise_ratio

from ddp_lite.evaluation.metrics import d1_error, hole_rmse, mae, point_cloud_prf, psnr, rmse


def test_rmse_and_mae_on_a_2x2_example():
    pred = np.array([[1.0, 2.0], [3.0, 4.0]], np.float32)
    gt = np.array([[1.0, 2.0], [3.0, 6.0]], np.float32)
    before = pred.copy(), gt.copy()
    assert rmse(pred, gt) == pytest.approx(1.0)  # √(2² / 4)
    assert mae(pred, gt) == pytest.approx(0.5)  # 2 / 4
    mask = np.array([[True, True], [True, False]])
    assert rmse(pred, gt, mask) == 0.0 and mae(pred, gt, mask) == 0.0
    np.testing.assert_array_equal(pred, before[0])
    np.testing.assert_array_equal(gt, before[1])


def test_default_mask_is_finite_truth_and_hole_rmse_is_rmse_in_the_holes():
    gt = np.array([[1.0, np.nan], [3.0, 5.0]])
    pred = np.array([[2.0, 7.0], [3.0, 2.0]])
    assert rmse(pred, gt) == pytest.approx(np.sqrt((1 + 0 + 9) / 3))  # the NaN pixel is left out
    assert mae(pred, gt) == pytest.approx(4 / 3)
    holes = np.array([[False, False], [True, True]])
    assert hole_rmse(pred, gt, holes) == pytest.approx(np.sqrt(9 / 2))
    assert hole_rmse(pred, gt, holes) == rmse(pred, gt, mask=holes)


def test_metric_inputs_are_checked():
    a = np.ones((2, 2))
    with pytest.raises(ValueError, match="same shape"):
        rmse(a, np.ones((2, 3)))
    with pytest.raises(ValueError, match="selects no pixel"):
        rmse(a, a, mask=np.zeros((2, 2), bool))
    with pytest.raises(ValueError, match="selects no pixel"):
        mae(a, np.full((2, 2), np.nan))
    with pytest.raises(ValueError, match="pred must be finite"):
        rmse(np.array([[np.nan, 1.0], [1.0, 1.0]]), a)
    with pytest.raises(TypeError, match="mask must be a bool"):
        rmse(a, a, mask=np.ones((2, 2)))
    with pytest.raises(ValueError, match="holes"):
        hole_rmse(a, a, None)
    with pytest.raises(ValueError, match="tau"):
        point_cloud_prf(np.zeros((1, 3)), np.zeros((1, 3)), tau=0)
    with pytest.raises(ValueError, match=r"pred_points must be \(N, 3\)"):
        point_cloud_prf(np.zeros((4, 2)), np.zeros((1, 3)), tau=1.0)
    with pytest.raises(ValueError, match="data_range"):
        psnr(a, a, data_range=-1.0)


def test_d1_counts_bad_pixels_by_hand():
    gt = np.array([[10.0, 10.0, 100.0, 100.0],
                   [50.0, np.nan, 20.0, 40.0]])
    pred = np.array([[10.0, 13.5, 104.0, 106.0],
                     [np.nan, 999.0, 22.9, 36.0]])
    # (0,0) exact: good            (0,1) 3.5 px > 3 and 35 % > 5 %: bad
    # (0,2) 4 px > 3 but 4 % < 5 %: good (the 3-px-but-under-5 % case)
    # (0,3) 6 px and 6 %: bad      (1,0) NaN prediction: bad
    # (1,1) no ground truth: not counted
    # (1,2) 2.9 px < 3 (though 14.5 %): good   (1,3) 4 px and 10 %: bad
    result = d1_error(pred, gt)
    assert result["d1_all"] == pytest.approx(4 / 7)
    assert result["d1_bg"] == pytest.approx(4 / 7)  # no fg mask: everything is background
    assert np.isnan(result["d1_fg"])
    fg = np.zeros(gt.shape, bool)
    fg[:, :2] = True  # valid fg pixels (0,0), (0,1), (1,0): 2 bad
    result = d1_error(pred, gt, fg)
    assert result["d1_fg"] == pytest.approx(2 / 3)
    assert result["d1_bg"] == pytest.approx(2 / 4)  # (0,2), (0,3), (1,2), (1,3): 2 bad
    assert result["d1_all"] == pytest.approx(4 / 7)
    assert d1_error(gt, gt)["d1_all"] == 0.0
    with pytest.raises(ValueError, match="disp_gt has no valid pixel"):
        d1_error(pred, np.full(gt.shape, np.nan))


def test_psnr_matches_scikit_image():
    rng = np.random.default_rng(0)
    target = rng.random((16, 20, 3)).astype(np.float32)
    pred = np.clip(target + rng.normal(0, 0.05, target.shape), 0, 1).astype(np.float32)
    expected = peak_signal_noise_ratio(target, pred, data_range=1.0)
    assert psnr(pred, target) == pytest.approx(expected, rel=1e-6)
    assert psnr(pred * 10, target * 10, data_range=10.0) == pytest.approx(expected, rel=1e-5)
    mask = np.zeros((16, 20), bool)
    mask[4:12, 5:15] = True  # an (H, W) mask applies to every channel
    expected_masked = peak_signal_noise_ratio(target[mask], pred[mask], data_range=1.0)
    assert psnr(pred, target, mask=mask) == pytest.approx(expected_masked, rel=1e-6)
    assert psnr(target, target) == float("inf")
    assert psnr(np.full((2, 2), 0.5), np.full((2, 2), 0.6)) == pytest.approx(20.0)  # MSE 0.01


def test_point_cloud_prf_on_point_sets_with_known_distances():
    import open3d as o3d
    pred = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [5.0, 0.0, 0.0]])
    gt = np.array([[0.0, 0.0, 0.1], [1.0, 0.0, 0.3]])
    # pred → gt: 0.1, 0.3, ~4.0;   gt → pred: 0.1, 0.3
    r = point_cloud_prf(pred, gt, tau=0.2)
    assert (r["precision"], r["recall"]) == pytest.approx((1 / 3, 1 / 2))
    assert r["fscore"] == pytest.approx(2 * (1 / 3) * (1 / 2) / (1 / 3 + 1 / 2))  # 0.4
    r = point_cloud_prf(pred, gt, tau=0.5)
    assert (r["precision"], r["recall"], r["fscore"]) == pytest.approx((2 / 3, 1.0, 0.8))
    cloud = o3d.geometry.PointCloud(o3d.utility.Vector3dVector(pred))
    assert point_cloud_prf(cloud, gt, tau=0.5) == point_cloud_prf(pred, gt, tau=0.5)  # clouds or arrays
    r = point_cloud_prf(pred, gt + 100.0, tau=0.5)
    assert r == {"precision": 0.0, "recall": 0.0, "fscore": 0.0}  # F is 0, not NaN, when P = R = 0


def test_d1_scaled_threshold_by_hand():
    # errors 0.2, 0.1, 0.6 px on truths 2, 2, 10: with 0.15 px and 5 % (0.1, 0.1, 0.5 px) pixels 0 and 2 are bad
    gt = np.array([2.0, 2.0, 10.0])
    pred = np.array([2.2, 2.1, 10.6])
    assert d1_error(pred, gt, abs_threshold=0.15)["d1_all"] == pytest.approx(2 / 3)
    assert d1_error(pred, gt)["d1_all"] == 0.0  # KITTI's 3 px: nothing is an outlier at this scale
    with pytest.raises(ValueError, match="abs_threshold"):
        d1_error(pred, gt, abs_threshold=-1.0)
