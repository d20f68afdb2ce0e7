"""ConstantTarget: a target's work done once per fit gives the numbers of the plain computation."""
import numpy as np
import pytest
import torch
import torch.nn.functional as F
from skimage.metrics import structural_similarity

from ddp_lite.method.paper.losses import disparity_loss, rgb_loss, ssim, warp_loss
from ddp_lite.method.paper.losses import ConstantTarget


def blur(x, sigma=1.5, size=11):  # an independent Gaussian: one 2-D kernel, no separability
    g = torch.exp(-(torch.arange(size, dtype=x.dtype) - size // 2) ** 2 / (2 * sigma ** 2))
    g = g / g.sum()
    kernel = (g[:, None] * g[None, :]).expand(x.shape[1], 1, size, size)
    return F.conv2d(x, kernel, groups=x.shape[1])


def reference_ssim(x, y):  # Wang et al. 2004 written out, 5 moments every call
    mu_x, mu_y = blur(x), blur(y)
    var_x, var_y, cov = blur(x * x) - mu_x ** 2, blur(y * y) - mu_y ** 2, blur(x * y) - mu_x * mu_y
    c1, c2 = 0.01 ** 2, 0.03 ** 2
    return (((2 * mu_x * mu_y + c1) * (2 * cov + c2)) / ((mu_x ** 2 + mu_y ** 2 + c1) * (var_x + var_y + c2))).mean()


def reference_l1_ssim(x, y, mask, l1_weight):  # the earlier formula: holes → 0, output made to agree outside mask
    if mask is not None:
        y = torch.where(mask, y, torch.zeros_like(y))
        x = torch.where(mask, x, y)
        l1 = ((x - y).abs() * mask).sum() / (mask.sum() * x.shape[1])
    else:
        l1 = (x - y).abs().mean()
    return l1_weight * l1 + (1 - l1_weight) * (1 - reference_ssim(x, y))


def random_case(channels, seed, dtype=torch.float64):
    g = torch.Generator().manual_seed(seed)
    x = torch.rand(1, channels, 29, 37, generator=g, dtype=dtype)
    y = (x + 0.3 * torch.randn(x.shape, generator=g, dtype=dtype)).clamp(0, 1)
    mask = torch.rand(1, 1, 29, 37, generator=g) > 0.3
    mask[..., 8:18, 10:25] = False  # a hole bigger than the window
    return x.requires_grad_(), y, mask


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_ssim_with_a_constant_target_matches_skimage_and_the_plain_call(seed):
    x, y, _ = random_case(3, seed)
    cached = ssim(x, ConstantTarget(y))
    plain = ssim(x, y)
    skimage = structural_similarity(x.detach()[0].permute(1, 2, 0).numpy(), y[0].permute(1, 2, 0).numpy(),
                                    gaussian_weights=True, sigma=1.5, use_sample_covariance=False, data_range=1.0,
                                    channel_axis=-1)
    assert abs(cached.item() - skimage) < 1e-6
    assert abs(cached.item() - plain.item()) < 1e-12
    grad_cached, = torch.autograd.grad(cached, x)
    grad_plain, = torch.autograd.grad(plain, x)
    torch.testing.assert_close(grad_cached, grad_plain, rtol=0, atol=1e-12)


@pytest.mark.parametrize("dtype, tol", [(torch.float64, 1e-12), (torch.float32, 1e-6)])
@pytest.mark.parametrize("seed", [0, 1])
def test_losses_with_constant_targets_equal_the_uncached_formula_value_and_gradient(seed, dtype, tol):
    out, target, mask = random_case(4, seed, dtype)
    target[:, :1][~mask] = 123.0  # ground truth inside the holes must not matter
    disp, rgb = out[:, :1], out[:, 1:4]
    warped = [(rgb.detach() + 0.1 * k).clamp(0, 1) * rgb for k in (1, 2)]
    valid = [mask, torch.roll(mask, 5, dims=-1)]
    disp_target, rgb_target = ConstantTarget(target[:, :1], mask), ConstantTarget(target[:, 1:4])
    cached = (disparity_loss(disp, disp_target, lambda_z=0.8), rgb_loss(rgb, rgb_target, lambda_i=0.5),
              warp_loss(rgb_target, warped, valid, 0.5), rgb_loss(rgb, ConstantTarget(target[:, 1:4], mask), lambda_i=0.5))
    plain = (disparity_loss(disp, target[:, :1], mask, 0.8), rgb_loss(rgb, target[:, 1:4], lambda_i=0.5),
             warp_loss(target[:, 1:4], warped, valid, 0.5), rgb_loss(rgb, target[:, 1:4], mask, 0.5))
    reference = (reference_l1_ssim(disp, target[:, :1], mask, 0.8), reference_l1_ssim(rgb, target[:, 1:4], None, 0.5),
                 torch.stack([_warp_reference(w, target[:, 1:4], v) for w, v in zip(warped, valid)]).mean(),
                 reference_l1_ssim(rgb, target[:, 1:4], mask, 0.5))
    for a, b, r in zip(cached, plain, reference):
        assert abs(a.item() - b.item()) <= tol and abs(a.item() - r.item()) <= 10 * tol
        grad_a, grad_b, grad_r = (torch.autograd.grad(loss, out, retain_graph=True)[0] for loss in (a, b, r))
        torch.testing.assert_close(grad_a, grad_b, rtol=0, atol=tol)
        torch.testing.assert_close(grad_a, grad_r, rtol=0, atol=10 * tol)
    grad, = torch.autograd.grad(cached[0], out)
    assert torch.all(grad[:, :1][~mask] == 0)  # nothing flows into the holes


def _warp_reference(warped, reference, valid):  # L_warp per neighbour: λw SSIM, the reference is not masked
    x = torch.where(valid, warped, reference)
    l1 = ((x - reference).abs() * valid).sum() / (valid.sum() * x.shape[1])
    return 0.5 * l1 + 0.5 * (1 - reference_ssim(x, reference))


def test_a_prepared_target_refuses_a_second_mask():
    _, y, mask = random_case(1, 0)
    with pytest.raises(ValueError, match="ConstantTarget"):
        disparity_loss(torch.rand_like(y), ConstantTarget(y, mask), mask.clone())
    with pytest.raises(ValueError, match="mask"):
        disparity_loss(torch.rand_like(y), y)


def test_rgb_loss_takes_its_arguments_in_disparity_loss_order_and_refuses_a_weight_as_mask():
    from ddp_lite.method.paper.losses import rgb_loss
    rgb, target = torch.full((1, 3, 16, 16), 0.25), torch.full((1, 3, 16, 16), 0.75)
    mask = torch.zeros(1, 1, 16, 16, dtype=torch.bool)
    mask[..., :8] = True
    # L1 only (lambda_i = 1): |0.25 - 0.75| = 0.5 on every counted pixel, with or without the mask
    assert rgb_loss(rgb, target, mask, 1.0).item() == pytest.approx(0.5)
    assert rgb_loss(rgb, target, lambda_i=1.0).item() == pytest.approx(0.5)
    with pytest.raises(TypeError, match="mask"):
        rgb_loss(rgb, target, 0.5)
