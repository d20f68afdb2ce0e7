"""The warp's occlusion test (``Visibility``, ``Warper(visibility=...)``, ``FitConfig.warp_occlusion``)
against geometry worked out by hand: a rectified pair with a box in front of a wall, a plane steep
in depth, and the ordering test of rectified stereo on the real Motorcycle pair's ground truth."""
import numpy as np
import pytest
import torch

from ddp_lite.core.camera import Camera, look_at
from ddp_lite.method.config import FitConfig
from ddp_lite.method.kit.visibility import Visibility
from ddp_lite.method.paper.warp import Warper

FOCAL, BASELINE, WIDTH, HEIGHT = 40.0, 0.2, 64, 8


def rectified_pair():
    """Left camera at the origin, right camera BASELINE m to its right: disparity d = f·B/Z px."""
    K = np.array([[FOCAL, 0.0, WIDTH / 2], [0.0, FOCAL, HEIGHT / 2], [0.0, 0.0, 1.0]])
    right = np.eye(4)
    right[0, 3] = -BASELINE  # cam_from_world: x_right = x_world - B
    return Camera(K, np.eye(4), WIDTH, HEIGHT), Camera(K, right, WIDTH, HEIGHT)


def hidden_and_inside(ref, nbr, depth):
    """(H, W) bool each: hidden from ``nbr``, and landing inside its image."""
    _, inside = Warper(ref, nbr)(torch.rand(1, 3, nbr.height, nbr.width), depth)
    return Visibility(ref, nbr)(depth)[0, 0].numpy(), inside[0, 0].numpy()


@pytest.mark.parametrize("band", [2, 5])
def test_the_band_left_of_a_box_is_hidden_from_the_right_camera(band):
    # A wall at d_b = 2 px and a box over columns [30, 40) at d_f = 2 + band px. The right camera
    # shifts the box `band` px further left than the wall, over the wall's columns [30 - band, 30).
    left, right = rectified_pair()
    wall, box = FOCAL * BASELINE / 2.0, FOCAL * BASELINE / (2.0 + band)
    depth = torch.full((1, 1, HEIGHT, WIDTH), wall)
    depth[..., 30:40] = box
    hidden, inside = hidden_and_inside(left, right, depth)
    expected = np.zeros((HEIGHT, WIDTH), bool)
    expected[:, 30 - band + 1:30] = True  # column 30 - band is grazed: its ray to the right camera touches the box's corner
    grazed = np.zeros((HEIGHT, WIDTH), bool)
    grazed[:, 30 - band] = True
    np.testing.assert_array_equal(hidden[inside & ~grazed], expected[inside & ~grazed])


def test_a_plane_steep_in_depth_hides_nothing_of_itself():
    # Inverse depth is affine in the pixel coordinates on any plane; here it changes ~10 % per row
    # (a floor near the horizon). Both cameras see the same side of it, so nothing is hidden.
    ref = Camera.from_fov(48, 24, 60.0)
    nbr = Camera(ref.K, look_at([0.15, 0.05, 0.0], [0.0, 0.0, 3.0]), 48, 24)
    v, u = np.mgrid[0:24, 0:48].astype(np.float32)
    inverse = 0.1 + 0.04 * v + 0.002 * u  # 1/m
    hidden, inside = hidden_and_inside(ref, nbr, torch.from_numpy(1.0 / inverse)[None, None])
    assert inside.mean() > 0.5
    assert not hidden[inside].any()


def test_the_test_only_removes_pixels_and_leaves_the_warped_image_alone():
    left, right = rectified_pair()
    depth = torch.full((1, 1, HEIGHT, WIDTH), FOCAL * BASELINE / 2.0)
    depth[..., 30:40] = FOCAL * BASELINE / 6.0
    image = torch.rand(1, 3, HEIGHT, WIDTH)
    plain, inside = Warper(left, right)(image, depth)
    tested, visible = Warper(left, right, visibility=Visibility(left, right))(image, depth)
    assert torch.equal(plain, tested)
    assert bool((visible <= inside).all()) and 3 * HEIGHT <= int((inside & ~visible).sum()) <= 4 * HEIGHT


def test_warp_occlusion_reaches_the_fit_and_is_checked():
    from ddp_lite.method.paper.disparity import DisparityTransform
    from ddp_lite.method.kit.warp_terms import kit_warp_arguments
    from ddp_lite.method.paper.total_loss import PaperLoss

    left, right = rectified_pair()
    transform = DisparityTransform.from_depth(np.full((HEIGHT, WIDTH), 4.0, np.float32))
    target, mask, rgb = torch.zeros(1, 1, HEIGHT, WIDTH), torch.ones(1, 1, HEIGHT, WIDTH, dtype=torch.bool), torch.rand(1, 3, HEIGHT, WIDTH)
    for flag in (False, True):
        config, pairs = FitConfig(warp_occlusion=flag), [(torch.rand(1, 3, HEIGHT, WIDTH), right)]
        loss = PaperLoss("rgbd+warp", config.paper, transform, target, mask, rgb, left, pairs,
                         **kit_warp_arguments(config.warp, config.paper.lambda_w, transform, mask, rgb, left, pairs, "cpu"))
        assert (loss.warpers[0].visibility is not None) is flag
    with pytest.raises(TypeError, match="config.warp_occlusion"):
        FitConfig(warp_occlusion="yes").validate()


def test_on_the_real_pair_it_agrees_with_the_ordering_test_of_rectified_stereo():
    # Rectified stereo, left reference: the right camera cannot see left pixel x when some pixel
    # x' > x of its row lands at or left of it in the right image (the order of the row flips).
    from ddp_lite.data.middlebury import load_motorcycle
    from ddp_lite.studies.real_cases import pool_scene

    scene = pool_scene(load_motorcycle(), 4)
    left, right = scene[0], scene.right[0]
    depth = np.where(np.isfinite(left.depth), left.depth, np.nanmedian(left.depth)).astype(np.float32)
    depth_t = torch.from_numpy(depth)[None, None]
    warper = Warper(left.camera, right.camera)
    q = depth_t * warper.rays + warper.offset
    landing = (q[0, 0] / q[0, 2]).numpy()  # (H, W) column in the right image
    rightmost = np.minimum.accumulate(landing[:, ::-1], axis=1)[:, ::-1]
    right_of = np.concatenate([rightmost[:, 1:], np.full((landing.shape[0], 1), np.inf)], axis=1)
    ordering = right_of < landing - 0.5  # a flip by more than half a pixel
    hidden, inside = hidden_and_inside(left.camera, right.camera, depth_t)
    a, b = ordering & inside, hidden & inside
    assert 0.05 < b.mean() < 0.3  # the pair has wide occluded bands
    assert (a & b).sum() / (a | b).sum() > 0.95


def test_the_equation_marks_the_visible_warp_term_as_the_kits():
    from ddp_lite.method.equation import loss_equation
    warp = loss_equation(FitConfig.for_profile("class", variant="rgbd+warp", recipe="paper", warp_occlusion=True), "rgbd+warp")
    assert "0.02\\,\\underbrace{L^{\\mathrm{warp}}_{\\mathrm{visible}}}_{\\text{not in the paper}}" in warp
    rgbd = loss_equation(FitConfig.for_profile("class", variant="rgbd", recipe="paper", warp_occlusion=True), "rgbd")
    assert "visible" not in rgbd and "not in the paper" not in rgbd  # no warp term, nothing to mark
