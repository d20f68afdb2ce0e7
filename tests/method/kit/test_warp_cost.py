"""The warp term's other costs and its texture weights (``FitConfig.warp_cost``, ``FitConfig.warp_texture``,
``ddp_lite.method.kit.warp_cost``), against references computed by hand: the soft census of a 3×3 patch and
the soft Hamming distance of two sign patterns, costs under a constant brightness offset between the
views, the epipolar direction of a rectified pair, and where each cost's minimum lies on a pair built
with a known disparity."""
import numpy as np
import pytest
import torch
from scipy import ndimage

from ddp_lite.method.config import FitConfig
from ddp_lite.method.paper.disparity import DisparityTransform
from ddp_lite.method.paper.losses import ConstantTarget, warp_loss
from ddp_lite.method.kit.warp_terms import WarpConfig, kit_warp_arguments, kit_warp_term
from ddp_lite.method.paper.total_loss import PaperLoss
from ddp_lite.method.kit.recipes import describe_method
from ddp_lite.method.paper.warp import Warper
from ddp_lite.method.kit.warp_cost import (CENSUS_SCALE, WARP_COSTS, WarpCost, census_distance, epipolar_directions,
                                       soft_census, texture_weights)
from conftest import rectified_pair

FOCAL, BASELINE, WIDTH, HEIGHT, SHIFT = 60.0, 0.1, 64, 32, 6  # the pair's true disparity: 6 px


def textured_pair(seed=0, offset=0.0):
    """(reference, neighbour) (1, 3, HEIGHT, WIDTH): a smooth random texture seen SHIFT px apart (the
    neighbour is the right view), the neighbour ``offset`` brighter."""
    rng = np.random.default_rng(seed)
    canvas = ndimage.gaussian_filter(rng.random((HEIGHT, WIDTH + SHIFT, 3)), (1.0, 1.0, 0)).astype(np.float32)
    as_tensor = lambda image: torch.from_numpy(np.ascontiguousarray(image.transpose(2, 0, 1)))[None]
    return as_tensor(canvas[:, :WIDTH]), as_tensor(canvas[:, SHIFT:SHIFT + WIDTH] + offset)


def test_soft_census_of_a_3x3_patch_by_hand():
    patch = np.array([[0.2, 0.5, 0.5], [0.1, 0.5, 0.9], [0.5, 0.3, 0.8]], dtype=np.float64)
    epsilon = 0.01
    census = soft_census(torch.from_numpy(patch)[None, None], radius=1, epsilon=epsilon)
    assert census.shape == (1, 8, 3, 3)
    # at the centre, the neighbours row by row without the centre: d / sqrt(ε + d²)
    expected = [(v - 0.5) / np.sqrt(epsilon + (v - 0.5) ** 2) for v in (0.2, 0.5, 0.5, 0.1, 0.9, 0.5, 0.3, 0.8)]
    np.testing.assert_allclose(census[0, :, 1, 1].numpy(), expected, rtol=1e-12)
    # at a corner the patch repeats the border: the top-left pixel's up-left neighbour is itself (d = 0)
    assert float(census[0, 0, 0, 0]) == 0.0
    # equal neighbours give 0, and a tiny ε gives the hard census transform's signs
    hard = soft_census(torch.from_numpy(patch)[None, None], radius=1, epsilon=1e-16)[0, :, 1, 1].numpy()
    np.testing.assert_allclose(hard, [-1, 0, 0, -1, 1, 0, -1, 1], atol=1e-6)


def test_soft_hamming_distance_of_sign_patterns_by_hand():
    a = torch.tensor([1.0, -1.0, 1.0, 0.0, 1.0, -1.0, 1.0, 1.0]).reshape(1, 8, 1, 1)
    b = torch.tensor([1.0, 1.0, -1.0, 1.0, 1.0, -1.0, 1.0, 1.0]).reshape(1, 8, 1, 1)
    # two flipped signs (δ = 2: 4 / 4.1 each), one sign against 0 (δ = 1: 1 / 1.1), five equal, of 8
    expected = (2 * 4 / 4.1 + 1 / 1.1) / 8
    assert float(census_distance(a, b, eta=0.1)) == pytest.approx(expected, rel=1e-6)
    assert float(census_distance(a, a)) == 0.0


def test_census_and_gradient_costs_ignore_a_constant_brightness_offset_the_intensity_l1_does_not():
    reference, _ = textured_pair()
    brighter = reference + 0.1
    valid = torch.ones(1, 1, HEIGHT, WIDTH, dtype=torch.bool)
    # λw = 0: the L1 parts alone (the census ignores λw)
    assert float(WarpCost(reference, "intensity", lambda_w=0.0)(brighter, valid)) == pytest.approx(0.1, rel=1e-5)
    assert float(WarpCost(reference, "gradient", lambda_w=0.0)(brighter, valid)) == pytest.approx(0.0, abs=1e-6)
    assert float(WarpCost(reference, "census")(brighter, valid)) == pytest.approx(0.0, abs=1e-6)
    for kind in WARP_COSTS:  # and every cost is 0 for the reference itself
        assert float(WarpCost(reference, kind)(reference.clone(), valid)) == pytest.approx(0.0, abs=1e-6)


def test_the_intensity_cost_is_the_papers_warp_term_and_unit_weights_change_nothing():
    reference, neighbour = textured_pair(seed=1)
    valid = torch.rand(1, 1, HEIGHT, WIDTH, generator=torch.Generator().manual_seed(0)) > 0.3
    paper = warp_loss(ConstantTarget(reference), [neighbour], [valid], 0.5)
    cost = WarpCost(ConstantTarget(reference), "intensity", 0.5)
    assert torch.equal(cost(neighbour, valid), paper)  # bit for bit: the same code path
    ones = torch.ones(1, 1, HEIGHT, WIDTH)
    assert float(cost(neighbour, valid, ones)) == pytest.approx(float(paper), rel=1e-5)
    for kind in ("census", "gradient"):
        plain = WarpCost(reference, kind)
        assert float(plain(neighbour, valid, ones)) == pytest.approx(float(plain(neighbour, valid)), rel=1e-5)


def test_the_epipolar_direction_of_a_rectified_pair_is_x_and_the_weights_follow_change_along_it():
    left, right = rectified_pair(WIDTH, HEIGHT, FOCAL, BASELINE)
    directions = epipolar_directions(left, right)
    assert directions.shape == (1, 2, HEIGHT, WIDTH)
    np.testing.assert_allclose(directions[0, 0].abs().numpy(), 1.0, atol=1e-12)
    np.testing.assert_allclose(directions[0, 1].numpy(), 0.0, atol=1e-12)
    # left half: stripes across x (change along the epipolar line); right half: stripes across y (none)
    image = torch.zeros(1, 3, HEIGHT, WIDTH)
    columns, rows = torch.arange(WIDTH), torch.arange(HEIGHT)
    image[..., :, : WIDTH // 2] = ((columns[: WIDTH // 2] // 2) % 2).float()
    image[..., :, WIDTH // 2:] = ((rows[:, None] // 2) % 2).float().expand(HEIGHT, WIDTH // 2)
    weights = texture_weights(image, directions)[0, 0]
    assert float(weights.mean()) == pytest.approx(1.0, rel=1e-5)
    assert float(weights[:, 2:WIDTH // 2 - 2].min()) > 1.0  # every pixel of the x-stripes sees an edge along x
    assert float(weights[:, WIDTH // 2 + 2:].max()) == 0.0  # nothing changes along x there
    assert torch.equal(texture_weights(torch.ones(1, 3, 8, 8), directions[..., :8, :8]), torch.ones(1, 1, 8, 8))


@pytest.mark.parametrize("kind", WARP_COSTS)
def test_each_cost_is_least_at_the_true_disparity_of_a_textured_pair(kind):
    reference, neighbour = textured_pair(seed=2, offset=0.05 if kind != "intensity" else 0.0)
    left, right = rectified_pair(WIDTH, HEIGHT, FOCAL, BASELINE)
    warper, cost = Warper(left, right), WarpCost(reference, kind)
    values = {}
    for disparity in range(2, 11):
        warped, valid = warper(neighbour, torch.full((1, 1, HEIGHT, WIDTH), FOCAL * BASELINE / disparity))
        values[disparity] = float(cost(warped, valid))
    assert min(values, key=values.get) == SHIFT, values


def test_paper_loss_with_another_cost_or_the_weights_pulls_the_depth_and_the_default_is_the_papers():
    reference, neighbour = textured_pair(seed=3)
    left, right = rectified_pair(WIDTH, HEIGHT, FOCAL, BASELINE)
    transform = DisparityTransform(FOCAL * BASELINE / 14.0, FOCAL * BASELINE / 1.0)
    mask = torch.ones(1, 1, HEIGHT, WIDTH, dtype=torch.bool)
    mask[..., 10:18, 20:28] = False
    target = torch.full((1, 1, HEIGHT, WIDTH), 0.4)
    assert kit_warp_term(WarpConfig(), 0.5, transform, mask, reference, left, [(neighbour, right)], "cpu") is None
    for settings in (dict(warp_cost="census"), dict(warp_cost="gradient"), dict(warp_cost="census+intensity"),
                     dict(warp_texture=True)):
        config, pairs = FitConfig(**settings), [(neighbour, right)]
        loss = PaperLoss("rgbd+warp", config.paper, transform, target, mask, reference, left, pairs,
                         **kit_warp_arguments(config.warp, config.paper.lambda_w, transform, mask, reference, left, pairs, "cpu"))
        disparity = torch.full((1, 1, HEIGHT, WIDTH), 0.4, requires_grad=True)
        _, terms = loss(disparity, reference.clone())
        terms["warp"].backward()
        assert torch.isfinite(disparity.grad).all() and int((disparity.grad != 0).sum()) > HEIGHT * WIDTH // 2, settings


def test_the_options_are_checked_off_by_default_and_named_as_the_kits():
    config = FitConfig()
    assert config.warp.cost == "intensity" and config.warp.texture is False
    FitConfig(warp_cost="census", warp_texture=True).validate()
    with pytest.raises(ValueError, match="config.warp_cost"):
        FitConfig(warp_cost="ncc").validate()
    with pytest.raises(TypeError, match="config.warp_texture"):
        FitConfig(warp_texture=1).validate()
    assert "census" in describe_method({"warp_cost": "census"})
    assert "epipolar" in describe_method({"warp_texture": True})


def test_census_plus_intensity_is_half_the_papers_cost_and_half_the_census_at_its_size():
    generator = torch.Generator().manual_seed(4)
    reference, warped = torch.rand(1, 3, 24, 40, generator=generator), torch.rand(1, 3, 24, 40, generator=generator)
    valid = torch.rand(1, 1, 24, 40, generator=generator) > 0.2
    weights = torch.rand(1, 1, 24, 40, generator=generator) * 2
    mixed, intensity, census = (WarpCost(reference, kind) for kind in ("census+intensity", "intensity", "census"))
    assert CENSUS_SCALE == 0.59
    for w in (None, weights):  # each half through the single costs' own code, with and without the weights
        expected = 0.5 * float(intensity(warped, valid, w)) + 0.5 * 0.59 * float(census(warped, valid, w))
        assert float(mixed(warped, valid, w)) == pytest.approx(expected, rel=1e-6), w is None
    # the halves differ on random images, so a wrong mix (e.g. the census unscaled, or one half only) shows
    assert abs(float(intensity(warped, valid)) - 0.59 * float(census(warped, valid))) > 0.01
    # without weights the intensity half is the paper's term, bit for bit
    paper = warp_loss(ConstantTarget(reference), [warped], [valid], 0.5)
    assert float(mixed(warped, valid)) == pytest.approx(0.5 * float(paper) + 0.5 * 0.59 * float(census(warped, valid)), rel=1e-6)
    # identical images (and whatever the invalid pixels hold): 0
    scrambled = torch.where(valid, reference, warped)
    assert float(mixed(scrambled, valid)) == pytest.approx(0.0, abs=1e-7)
    assert float(mixed(scrambled, valid, weights)) == pytest.approx(0.0, abs=1e-7)
    FitConfig(warp_cost="census+intensity").validate()
    assert "census" in describe_method({"warp_cost": "census+intensity"})
