"""The warp term's confidence mask (``warp_confidence``, ``FitConfig.warp_confidence``) against stereo pairs
built by hand: a plane with a textured and a flat part, a box in front of a wall (the band the right camera
cannot see), the per-pixel cost against the warp loss it mirrors, and the fit's gradient where it is off."""
import numpy as np
import pytest
import torch
from scipy import ndimage

from ddp_lite.method.config import FitConfig
from ddp_lite.method.paper.losses import ssim, warp_loss
from ddp_lite.method.kit.warp_confidence import cost_volume, photometric_cost, sweep_planes, warp_confidence
from ddp_lite.method.paper.warp import Warper
from conftest import rectified_pair

FOCAL, BASELINE, WIDTH, HEIGHT = 60.0, 0.1, 96, 40
D_MIN, D_MAX = FOCAL * BASELINE / 14.0, FOCAL * BASELINE / 1.0  # disparities 1-14 px


def texture(width, seed):
    """(HEIGHT, width, 3) random colour, blurred by 1 px: texture every window can match."""
    noise = np.random.default_rng(seed).random((HEIGHT, width, 3))
    return ndimage.gaussian_filter(noise, (1.0, 1.0, 0)).astype(np.float32)


def as_tensor(image):
    return torch.from_numpy(np.ascontiguousarray(image.transpose(2, 0, 1)))[None]


def test_a_textured_plane_is_confident_and_its_flat_part_is_not():
    # A fronto-parallel plane at disparity 6 px: the right image is the left one moved 6 px left
    # (I_right(u) = I_left(u + 6)). Columns from 64 on are one flat grey in both.
    d = 6
    canvas = texture(WIDTH + d, seed=0)
    canvas[:, 64:] = 0.5
    left_image, right_image = canvas[:, :WIDTH], canvas[:, d:d + WIDTH]
    left, right = rectified_pair(WIDTH, HEIGHT, FOCAL, BASELINE)
    confident = warp_confidence(as_tensor(left_image), as_tensor(right_image), left, right, D_MIN, D_MAX)[0, 0].numpy()
    textured = confident[:, d + 8:56]  # seen by the right camera, 8 px from the flat part
    flat = confident[:, 72:]
    assert textured.mean() > 0.95, textured.mean()
    assert flat.mean() < 0.05, flat.mean()
    assert confident[:, :d].mean() < 0.3  # the right camera does not see these columns at the true depth


def test_the_band_the_right_camera_cannot_see_is_not_confident():
    # A wall at d_b = 3 px and a box over columns [40, 64) at d_f = 11 px, both textured. The right camera
    # sees the box 8 px further left than the wall: the wall's columns [32, 40) are hidden behind it.
    left_image, right_image, band_columns = occluded_band_pair()
    left, right = rectified_pair(WIDTH, HEIGHT, FOCAL, BASELINE)
    confident = warp_confidence(as_tensor(left_image), as_tensor(right_image), left, right, D_MIN, D_MAX)[0, 0].numpy()
    band = confident[:, band_columns]
    assert band.mean() < 0.05, band.mean()
    assert confident[:, 10:26].mean() > 0.9  # the wall away from the band
    assert confident[:, 48:56].mean() > 0.9  # the box's inside


def test_the_cost_is_the_warp_loss_per_pixel():
    # Away from the border (where SSIM's map is padded) the mean of the per-pixel cost is the warp loss.
    generator = torch.Generator().manual_seed(0)
    reference, warped = torch.rand(1, 3, 32, 40, generator=generator), torch.rand(1, 3, 32, 40, generator=generator)
    cost = photometric_cost(reference, warped, lambda_w=0.5)
    assert cost.shape == (1, 1, 32, 40)
    l1 = (warped - reference).abs()[..., 5:-5, 5:-5].mean()
    expected = 0.5 * (1 - ssim(warped, reference)) + 0.5 * l1
    assert float(cost[..., 5:-5, 5:-5].mean()) == pytest.approx(float(expected), rel=1e-5)
    assert float(photometric_cost(reference, reference.clone()).abs().max()) < 1e-5
    # and the whole-image warp loss with every pixel valid weighs L1 and SSIM the same way
    loss = warp_loss(reference, [warped], [torch.ones(1, 1, 32, 40, dtype=torch.bool)])
    assert float(loss) == pytest.approx(float(0.5 * (1 - ssim(warped, reference)) + 0.5 * (warped - reference).abs().mean()),
                                         rel=1e-5)


def test_the_sweep_spans_the_range_at_the_step_asked_for():
    left, right = rectified_pair(WIDTH, HEIGHT, FOCAL, BASELINE)
    planes = sweep_planes(left, right, D_MIN, D_MAX, step_px=0.25)
    disparity = FOCAL * BASELINE / planes
    assert planes[0] == pytest.approx(D_MIN) and planes[-1] == pytest.approx(D_MAX)
    assert np.allclose(np.diff(disparity), -0.25, atol=1e-6)  # 14 → 1 px in steps of 0.25
    image = torch.rand(1, 3, HEIGHT, WIDTH)
    volume = cost_volume(image, image, Warper(left, right), planes[:5])
    assert volume.shape == (5, HEIGHT, WIDTH)
    assert torch.isinf(volume[0, :, :10]).all()  # 14 px of disparity sends these outside the right image


def test_the_fit_gets_no_pull_from_the_warp_term_where_it_is_not_confident():
    from ddp_lite.method.paper.disparity import DisparityTransform
    from ddp_lite.method.kit.warp_terms import WarpConfig, kit_warp_arguments, kit_warp_term
    from ddp_lite.method.paper.total_loss import PaperLoss

    d = 6
    canvas = texture(WIDTH + d, seed=0)
    canvas[:, 64:] = 0.5
    left, right = rectified_pair(WIDTH, HEIGHT, FOCAL, BASELINE)
    rgb, nbr = as_tensor(canvas[:, :WIDTH]), as_tensor(canvas[:, d:d + WIDTH])
    transform = DisparityTransform(D_MIN, D_MAX)
    target, mask = torch.zeros(1, 1, HEIGHT, WIDTH), torch.zeros(1, 1, HEIGHT, WIDTH, dtype=torch.bool)
    config = FitConfig(warp_confidence=True)
    loss = PaperLoss("rgbd+warp", config.paper, transform, target, mask, rgb, left, [(nbr, right)],
                     **kit_warp_arguments(config.warp, config.paper.lambda_w, transform, mask, rgb, left, [(nbr, right)], "cpu"))
    assert kit_warp_term(WarpConfig(), 0.5, transform, mask, rgb, left, [(nbr, right)], "cpu") is None  # the paper's term
    confident = loss.warp_term.keep[0]
    disparity = torch.full((1, 1, HEIGHT, WIDTH), 0.4, requires_grad=True)
    _, terms = loss(disparity, rgb.clone())
    terms["warp"].backward()
    gradient = disparity.grad.abs()
    assert float(gradient[~confident].max()) == 0.0
    assert float(gradient[confident].max()) > 0.0
    with pytest.raises(TypeError, match="config.warp_confidence"):
        FitConfig(warp_confidence="yes").validate()


def occluded_band_pair(d_wall=3, d_box=11, a=40, b=64):
    """The box-before-a-wall pair of the test above: (left image, right image) (H, W, 3) and the hidden band's columns."""
    wall, box = texture(WIDTH + d_box, seed=1), texture(WIDTH + d_box, seed=2)
    left_image = wall[:, :WIDTH].copy()
    left_image[:, a:b] = box[:, a:b]
    right_image = np.empty_like(left_image)
    for u in range(WIDTH):
        right_image[:, u] = box[:, u + d_box] if a <= u + d_box < b else wall[:, u + d_wall]
    return left_image, right_image, slice(a - (d_box - d_wall), a)


def test_the_left_right_check_alone_finds_the_band():
    left_image, right_image, band = occluded_band_pair()
    left, right = rectified_pair(WIDTH, HEIGHT, FOCAL, BASELINE)
    args = (as_tensor(left_image), as_tensor(right_image), left, right, D_MIN, D_MAX)
    checked = warp_confidence(*args, uniqueness=0.0, erode_px=0)[0, 0].numpy()
    unchecked = warp_confidence(*args, uniqueness=0.0, lr_tolerance_px=np.inf, erode_px=0)[0, 0].numpy()
    assert unchecked[:, band].mean() > 0.5  # the band's cost curve has some minimum: it alone does not tell
    assert checked[:, band].mean() < 0.25, checked[:, band].mean()


def test_uniqueness_alone_rejects_a_repeated_pattern():
    # Vertical stripes of period 4 px over the whole plane (disparity 6 px), the right camera exposed a little
    # differently (0.9·I + 0.05): 2, 6, 10 and 14 px match equally well, at the same non-zero cost.
    d = 6
    columns = np.arange(WIDTH + d)
    canvas = np.repeat((0.3 + 0.4 * (columns % 4 < 2))[None, :, None], 3, axis=2).repeat(HEIGHT, axis=0)
    left_image, right_image = canvas[:, :WIDTH].astype(np.float32), (0.9 * canvas[:, d:d + WIDTH] + 0.05).astype(np.float32)
    left, right = rectified_pair(WIDTH, HEIGHT, FOCAL, BASELINE)
    args = (as_tensor(left_image), as_tensor(right_image), left, right, D_MIN, D_MAX)
    unique = warp_confidence(*args, lr_tolerance_px=np.inf, erode_px=0)[0, 0].numpy()
    textured = texture(WIDTH + d, seed=3)  # the same plane, a texture that does not repeat
    other = warp_confidence(as_tensor(textured[:, :WIDTH]), as_tensor(textured[:, d:d + WIDTH]), left, right, D_MIN, D_MAX,
                            lr_tolerance_px=np.inf, erode_px=0)[0, 0].numpy()
    assert other[:, 20:].mean() > 0.9
    assert unique[:, 20:].mean() < 0.05, unique[:, 20:].mean()


def test_the_neighbourhood_is_a_square_erosion():
    left_image, right_image, _ = occluded_band_pair()
    left, right = rectified_pair(WIDTH, HEIGHT, FOCAL, BASELINE)
    args = (as_tensor(left_image), as_tensor(right_image), left, right, D_MIN, D_MAX)
    alone = warp_confidence(*args, erode_px=0)[0, 0].numpy()
    eroded = warp_confidence(*args, erode_px=2)[0, 0].numpy()
    np.testing.assert_array_equal(eroded, ndimage.binary_erosion(alone, np.ones((5, 5), bool), border_value=1))
    assert alone.sum() > eroded.sum() > 0
