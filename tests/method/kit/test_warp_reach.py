"""The warp term restricted to the holes (``FitConfig.warp_reach``, ``kit.warp_terms.warp_region``), against
masks and a stereo pair built by hand: which pixels the region holds, and that the fit's disparity gets
exactly no gradient from the warp term on the valid input outside it, and some inside."""
import numpy as np
import pytest
import torch
from scipy import ndimage

from ddp_lite.method.config import FitConfig
from ddp_lite.method.paper.disparity import DisparityTransform
from ddp_lite.method.kit.warp_terms import kit_warp_arguments, warp_region
from ddp_lite.method.paper.total_loss import PaperLoss
from conftest import rectified_pair

FOCAL, BASELINE, WIDTH, HEIGHT = 60.0, 0.1, 64, 32
D_MIN, D_MAX = FOCAL * BASELINE / 14.0, FOCAL * BASELINE / 1.0  # disparities 1-14 px


def fit_mask_with_a_hole(top=10, left=20, size=8):
    """(1, 1, HEIGHT, WIDTH) bool: valid everywhere but a size × size square hole."""
    mask = torch.ones(1, 1, HEIGHT, WIDTH, dtype=torch.bool)
    mask[..., top:top + size, left:left + size] = False
    return mask


def test_the_region_is_the_hole_and_a_ring_of_reach_px():
    mask = fit_mask_with_a_hole()
    hole = ~mask[0, 0].numpy()
    np.testing.assert_array_equal(warp_region(mask, 0.0)[0, 0].numpy(), hole)
    # reach 1: the 4-neighbours join (a cross-shaped dilation); √2 also the diagonal ones (a square)
    np.testing.assert_array_equal(warp_region(mask, 1.0)[0, 0].numpy(), ndimage.binary_dilation(hole))
    np.testing.assert_array_equal(warp_region(mask, 1.5)[0, 0].numpy(),
                                  ndimage.binary_dilation(hole, np.ones((3, 3), bool)))
    ring3 = warp_region(mask, 3.0)[0, 0].numpy()
    assert ring3[10 + 3, 20 - 3] and not ring3[10 + 3, 20 - 4]  # 3 px left of the hole's edge, not 4
    assert not warp_region(torch.ones(1, 1, 8, 8, dtype=torch.bool), 3.0).any()  # no hole: no region


def test_the_warp_term_passes_no_gradient_to_valid_pixels_outside_the_region():
    # A textured pair at 6 px of disparity and a disparity that is wrong everywhere: the plain warp
    # term pulls every pixel; restricted to the hole and 2 px around it, only those pixels.
    rng = np.random.default_rng(0)
    canvas = ndimage.gaussian_filter(rng.random((HEIGHT, WIDTH + 6, 3)), (1.0, 1.0, 0)).astype(np.float32)
    as_tensor = lambda image: torch.from_numpy(np.ascontiguousarray(image.transpose(2, 0, 1)))[None]
    rgb, nbr = as_tensor(canvas[:, :WIDTH]), as_tensor(canvas[:, 6:6 + WIDTH])
    left, right = rectified_pair(WIDTH, HEIGHT, FOCAL, BASELINE)
    transform = DisparityTransform(D_MIN, D_MAX)
    mask = fit_mask_with_a_hole()
    target = torch.full((1, 1, HEIGHT, WIDTH), 0.4)
    gradients = {}
    for reach in (None, 2.0):
        config = FitConfig(warp_reach=reach)
        loss = PaperLoss("rgbd+warp", config.paper, transform, target, mask, rgb, left, [(nbr, right)],
                         **kit_warp_arguments(config.warp, config.paper.lambda_w, transform, mask, rgb, left, [(nbr, right)], "cpu"))
        assert (loss.warp_term is None) is (reach is None)
        disparity = torch.full((1, 1, HEIGHT, WIDTH), 0.4, requires_grad=True)
        _, terms = loss(disparity, rgb.clone())
        terms["warp"].backward()
        gradients[reach] = disparity.grad.abs()[0, 0]
    region = torch.from_numpy(ndimage.distance_transform_edt(mask[0, 0].numpy()) <= 2.0)
    assert float(gradients[2.0][~region].max()) == 0.0  # exactly none on the valid input outside the ring
    assert float(gradients[2.0][region].min()) >= 0.0 and int((gradients[2.0][region] > 0).sum()) > region.sum() // 2
    assert int((gradients[None][~region] > 0).sum()) > (~region).sum() // 2  # the paper's term pulls there


def test_warp_reach_is_checked_and_marked_as_the_kits():
    from ddp_lite.method.equation import loss_equation
    from ddp_lite.method.kit.recipes import describe_method
    FitConfig(warp_reach=0.0).validate()
    with pytest.raises(ValueError, match="config.warp_reach"):
        FitConfig(warp_reach=-1.0).validate()
    with pytest.raises(TypeError, match="config.warp_reach"):
        FitConfig(warp_reach="3").validate()
    config = FitConfig.for_profile("class", variant="rgbd+warp", recipe="paper", warp_reach=3.0)
    assert "\\underbrace{L^{\\mathrm{warp}}_{\\mathrm{holes}}}_{\\text{not in the paper}}" in loss_equation(config, "rgbd+warp")
    assert "within 3 px" in describe_method({"warp_reach": 3.0})
