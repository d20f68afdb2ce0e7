"""SSIM, warping, the disparity transform and cameras, each against an independent reference."""
import numpy as np
import pytest
import torch
from skimage import data
from skimage.metrics import structural_similarity

from ddp_lite.core.camera import Camera, look_at, relative_pose
from ddp_lite.method.paper.disparity import DisparityTransform
from ddp_lite.method.paper.losses import ssim
from ddp_lite.method.paper.warp import warp_to_reference
from ddp_lite.core.camera import backproject, project


def skimage_ssim(x, y):
    return structural_similarity(x, y, gaussian_weights=True, sigma=1.5, use_sample_covariance=False,
                                 data_range=1.0, channel_axis=-1 if x.ndim == 3 else None)


@pytest.mark.parametrize("seed", [0, 1])
def test_ssim_matches_skimage_on_random_images(seed):
    rng = np.random.default_rng(seed)
    x = rng.random((40, 52)).astype(np.float64)
    y = np.clip(x + 0.2 * rng.standard_normal(x.shape), 0, 1)
    assert abs(ssim(x, y) - skimage_ssim(x, y)) < 1e-4


def test_ssim_matches_skimage_on_a_natural_colour_image():
    image = data.astronaut()[::4, ::4].astype(np.float64) / 255.0  # (128, 128, 3)
    noisy = np.clip(image + 0.1 * np.random.default_rng(0).standard_normal(image.shape), 0, 1)
    assert abs(ssim(image, noisy) - skimage_ssim(image, noisy)) < 1e-4
    blurred = (image + np.roll(image, 1, axis=0) + np.roll(image, 1, axis=1)) / 3
    assert abs(ssim(image, blurred) - skimage_ssim(image, blurred)) < 1e-4


def test_ssim_tensor_form_is_differentiable_and_one_on_identity():
    x = torch.rand(1, 3, 24, 24, dtype=torch.float64, requires_grad=True)
    value = ssim(x, x.detach())
    assert abs(value.item() - 1.0) < 1e-9
    (1 - ssim(x, torch.rand_like(x))).backward()
    assert torch.isfinite(x.grad).all() and x.grad.abs().sum() > 0


def test_ssim_refuses_small_or_mismatched_images():
    with pytest.raises(ValueError, match="at least 11"):
        ssim(np.zeros((8, 8)), np.zeros((8, 8)))
    with pytest.raises(ValueError, match="shape"):
        ssim(np.zeros((16, 16)), np.zeros((16, 17)))


def shifted_pair(baseline=0.1, depth=2.0, width=40, height=30):
    ref = Camera.from_fov(width, height, 60.0)
    pose = np.eye(4)
    pose[0, 3] = -baseline  # the neighbour sits `baseline` metres to the right of the reference
    return ref, Camera(ref.K, pose, width, height)


def test_identity_pose_returns_the_image():
    cam = Camera.from_fov(32, 24, 70.0)
    image = np.random.default_rng(0).random((24, 32, 3)).astype(np.float32)
    warped, valid = warp_to_reference(image, np.full((24, 32), 3.0, np.float32), cam, cam)
    assert valid.all()
    np.testing.assert_allclose(warped, image, atol=1e-5)


def test_fronto_parallel_plane_shifts_by_f_b_over_z():
    ref, nbr = shifted_pair()
    depth = ref.focal * 0.1 / 3.0  # chosen so that f·b/Z = 3 px exactly
    image = np.random.default_rng(1).random((30, 40, 3)).astype(np.float32)
    warped, valid = warp_to_reference(image, np.full((30, 40), depth, np.float32), ref, nbr)
    # ref pixel u sees the neighbour at u - f·b/Z = u - 3
    np.testing.assert_allclose(warped[:, 3:], image[:, :-3], atol=1e-4)
    assert not valid[:, :3].any() and valid[:, 4:].all()


def test_fractional_shift_on_a_linear_ramp_is_exact():
    ref, nbr = shifted_pair()
    depth = 2.0
    shift = ref.focal * 0.1 / depth
    u = np.arange(40, dtype=np.float32)
    image = np.repeat(np.broadcast_to(0.01 * u, (30, 40))[..., None], 3, axis=2).astype(np.float32)
    warped, valid = warp_to_reference(image, np.full((30, 40), depth, np.float32), ref, nbr)
    expected = 0.01 * (u - shift)
    np.testing.assert_allclose(warped[valid][:, 0], np.broadcast_to(expected, (30, 40))[valid], atol=1e-5)


def test_points_behind_or_outside_the_neighbour_are_invalid_and_nan_depth_too():
    ref, nbr = shifted_pair(baseline=5.0)
    depth = np.full((30, 40), 1.0, np.float32)
    depth[0, 0] = np.nan
    _, valid = warp_to_reference(np.zeros((30, 40, 3), np.float32), depth, ref, nbr)
    assert not valid.any()  # a 5 m shift at 1 m depth leaves the neighbour's image
    behind = Camera(ref.K, look_at([0, 0, 4.0], [0, 0, 0], up=(0, -1, 0)), 40, 30)  # looking back at us
    _, valid = warp_to_reference(np.zeros((30, 40, 3), np.float32), np.full((30, 40), 8.0, np.float32), ref, behind)
    assert not valid.any()


def test_warp_gradcheck_with_respect_to_depth():
    ref = Camera.from_fov(6, 5, 60.0)
    nbr = Camera(ref.K, look_at([0.05, 0.02, 0.0], [0.0, 0.0, 2.0]), 6, 5)
    image = torch.rand(1, 2, 5, 6, dtype=torch.float64)
    depth = (2.0 + 0.1 * torch.rand(1, 1, 5, 6, dtype=torch.float64)).requires_grad_()

    def warped_image(d):
        return warp_to_reference(image, d, ref, nbr)[0]

    assert torch.autograd.gradcheck(warped_image, (depth,), eps=1e-6, atol=1e-5)


def test_warp_uses_per_view_intrinsics():
    ref = Camera.from_fov(40, 30, 60.0)
    nbr = Camera.from_fov(20, 15, 60.0)  # same pose, half resolution
    v, u = np.mgrid[0:15, 0:20].astype(np.float32)
    image = np.stack([u / 20, v / 15, np.zeros_like(u)], axis=2)
    warped, valid = warp_to_reference(image, np.full((30, 40), 2.0, np.float32), ref, nbr)
    # ref pixel (u, v) is nbr pixel ((u + 0.5) / 2 - 0.5, (v + 0.5) / 2 - 0.5): pixel centres kept
    vv, uu = np.mgrid[0:30, 0:40].astype(np.float32)
    expected_u = ((uu + 0.5) / 2 - 0.5) / 20
    np.testing.assert_allclose(warped[..., 0][valid], expected_u[valid], atol=1e-5)


def test_backproject_then_project_round_trip_and_relative_pose():
    ref = Camera.from_fov(16, 12, 50.0)
    nbr = Camera(ref.K, look_at([0.3, 0.0, 0.0], [0.0, 0.0, 3.0]), 16, 12)
    K = torch.tensor(ref.K, dtype=torch.float64)  # a copy: Camera arrays are read-only
    depth = torch.full((1, 1, 12, 16), 3.0, dtype=torch.float64)
    points = backproject(depth, K)
    uv, z = project(points, K)
    v, u = torch.meshgrid(torch.arange(12.0, dtype=torch.float64), torch.arange(16.0, dtype=torch.float64), indexing="ij")
    assert torch.allclose(uv[0, 0], u) and torch.allclose(uv[0, 1], v) and torch.allclose(z, depth)
    world = np.array([0.2, -0.1, 3.0, 1.0])
    np.testing.assert_allclose(relative_pose(ref, nbr) @ (ref.cam_from_world @ world), nbr.cam_from_world @ world)


def test_look_at_follows_the_opencv_convention():
    pose = look_at([0, 0, 0], [0, 0, 5])  # looking down +z with -y up: the identity
    np.testing.assert_allclose(pose, np.eye(4), atol=1e-12)


def test_camera_refuses_bad_intrinsics():
    with pytest.raises(ValueError, match="K"):
        Camera(np.zeros((3, 3)), np.eye(4), 10, 10)
    with pytest.raises(ValueError, match="K"):
        Camera(np.eye(2), np.eye(4), 10, 10)
    with pytest.raises(ValueError, match="cam_from_world"):
        Camera(np.eye(3), np.diag([1.0, 1.0, 2.0, 1.0]), 10, 10)
    with pytest.raises(ValueError, match="width"):
        Camera(np.eye(3), np.eye(4), 0, 10)


def test_disparity_transform_by_hand_and_round_trip():
    t = DisparityTransform(d_min=1.0, d_max=9.0, constant=1.0)
    # Z = 1/(D + 1): near = 1/2, far = 1/10; D = 4 → Z = 1/5 → (0.2 - 0.1) / 0.4 = 0.25
    assert t.to_disparity(np.array([4.0]))[0] == pytest.approx(0.25)
    assert t.to_disparity(np.array([0.5]))[0] == pytest.approx(1.0)  # clipped to d_min
    assert t.to_disparity(np.array([50.0]))[0] == pytest.approx(0.0)  # clipped to d_max
    depth = np.linspace(1.0, 9.0, 50)
    np.testing.assert_allclose(t.to_depth(t.to_disparity(depth)), depth, rtol=1e-10)
    tensor = torch.linspace(1.0, 9.0, 5, dtype=torch.float64)
    assert torch.allclose(t.to_depth(t.to_disparity(tensor)), tensor)
    assert np.isnan(t.to_disparity(np.array([np.nan]))[0])


def test_disparity_transform_from_depth_and_the_papers_table():
    depth = np.array([[2.0, np.nan], [4.0, 8.0]])
    t = DisparityTransform.from_depth(depth)
    assert t.d_min < 2.0 and t.d_max > 8.0
    assert DisparityTransform.for_tnt_scene("Barn") == DisparityTransform(2.0, 16.5, 2.0)
    with pytest.raises(ValueError, match="d_min"):
        DisparityTransform(5.0, 1.0)
    with pytest.raises(ValueError, match="no finite"):
        DisparityTransform.from_depth(np.full((2, 2), np.nan))
