"""The Kinect-style hole and noise model against analytic cases: a box's shadow, a tilted plane, the z² steps."""
import numpy as np
import pytest

from ddp_lite.core.camera import Camera
from ddp_lite.classical.kinect import KINECT, grazing_mask, kinect_depth, kinect_holes, projector_shadow, quantise_depth
from ddp_lite.world.scenes import make_scene

H, W = 20, 80


def _box_scene(z_near=1.0, z_far=2.5, left=40, right=55):
    depth = np.full((H, W), z_far)
    depth[5:15, left:right] = z_near
    return depth


@pytest.mark.parametrize("offset", [0.075, -0.075, 0.2])
def test_shadow_of_a_box_matches_the_projector_geometry(offset):
    """Background pixel u (row through the box) is shadowed exactly when its projector column
    u − f·b/z_far lies within the box's projector columns, on the side away from the projector."""
    camera = Camera.from_fov(W, H, 60.0)
    f = camera.K[0, 0]
    z_near, z_far, left, right = 1.0, 2.5, 40, 55
    shadow = projector_shadow(_box_scene(z_near, z_far, left, right), camera, offset, tolerance=0.25)
    u = np.arange(W)
    box_columns = np.arange(left, right) - f * offset / z_near  # projector columns of the box's samples
    own = u - f * offset / z_far
    if offset > 0:  # hidden by a box sample to its right whose projector column is at or left of its own
        expected = (u < left) & (own > box_columns.min() + 0.25)
    else:
        expected = (u >= right) & (own < box_columns.max() - 0.25)
    np.testing.assert_array_equal(shadow[10], expected)
    assert not shadow[0].any() and not shadow[5:15, left:right].any()  # rows without the box, the box itself
    width = abs(f * offset * (1 / z_near - 1 / z_far))
    assert width - 1.5 <= expected.sum() <= width + 0.5  # f·b·(1/z_near − 1/z_far) px, sampled at pixel centres


def test_a_slanted_plane_facing_the_projector_is_lit():
    camera = Camera.from_fov(W, H, 60.0)
    u = np.arange(W)[None, :].repeat(H, 0)
    receding = 1.0 + 0.02 * u  # depth grows to the right, away from a projector on the right
    assert not projector_shadow(receding, camera, 0.075).any()
    assert not projector_shadow(receding[:, ::-1], camera, -0.075).any()


@pytest.mark.parametrize("tilt_deg, limit, expect_grazing", [(30.0, 75.0, False), (80.0, 75.0, True),
                                                             (60.0, 65.0, False), (70.0, 65.0, True)])
def test_grazing_mask_on_a_tilted_plane(tilt_deg, limit, expect_grazing):
    """A plane through (0, 0, 2) tilted about the y axis, seen at the image centre at ``tilt_deg``."""
    camera = Camera.from_fov(41, 41, 20.0)  # narrow: the viewing angle changes little across the image
    v, u = np.mgrid[0:41, 0:41].astype(float)
    rays = np.stack([u, v, np.ones_like(u)], -1) @ np.linalg.inv(camera.K).T
    normal = np.array([np.sin(np.radians(tilt_deg)), 0.0, np.cos(np.radians(tilt_deg))])
    depth = 2.0 * normal[2] / (rays @ normal)  # n·X = n·(0, 0, 2)
    centre = grazing_mask(depth, camera, limit)[15:26, 15:26]
    assert centre.all() if expect_grazing else not centre.any()


def test_quantised_depth_lies_on_the_disparity_lattice_with_z_squared_steps():
    f, b = 580.0, 0.075
    depth = np.linspace(0.8, 4.0, 20000)[None, :]  # denser than the lattice everywhere
    out = quantise_depth(depth, f, b, subpixel=8).astype(np.float64)
    levels = f * b / out * 8
    np.testing.assert_allclose(levels, np.round(levels), atol=1e-3)  # disparity on 1/8-px steps
    steps = np.diff(np.unique(out))
    z_mid = 0.5 * (np.unique(out)[1:] + np.unique(out)[:-1])
    np.testing.assert_allclose(steps, z_mid ** 2 / (8 * f * b), rtol=0.02)  # Δz ≈ z²/(8 f b)
    assert np.max(np.abs(out - depth)) <= np.max(depth ** 2) / (16 * f * b) * 1.05  # half a step at most


def test_depth_noise_grows_as_z_squared():
    f, b, sigma_d = 580.0, 0.075, 0.5
    errors = {}
    for z in (1.0, 2.0):
        out = quantise_depth(np.full((200, 200), z), f, b, subpixel=8, disparity_noise=sigma_d, seed=3)
        errors[z] = float(np.std(out - z))
        assert errors[z] == pytest.approx(z ** 2 * sigma_d / (f * b), rel=0.1)  # σ_z ≈ z² σ_d / (f b)
    assert errors[2.0] / errors[1.0] == pytest.approx(4.0, rel=0.1)


def test_range_dark_and_the_whole_reading():
    camera = Camera.from_fov(W, H, 60.0)
    depth = np.full((H, W), 2.0)
    depth[:, :10] = 0.3  # too near
    depth[:, -10:] = 6.0  # too far
    rgb = np.full((H, W, 3), 0.5, np.float32)
    rgb[:, 30:40] = 0.01  # a dark stripe
    causes = kinect_holes(depth, camera, rgb, seed=1, dark_dropout=0.5)
    assert causes["range"][:, :10].all() and causes["range"][:, -10:].all() and not causes["range"][:, 10:-10].any()
    assert 0.3 < causes["dark"][:, 30:40].mean() < 0.7 and not causes["dark"][:, :30].any()
    reading, mask = kinect_depth(depth, camera, rgb, seed=1, dark_dropout=0.5)
    missing = np.logical_or.reduce(list(causes.values()))
    np.testing.assert_array_equal(~mask, missing)
    step = 4.0 / (8 * KINECT["sensor_focal"] * KINECT["projector_offset"])
    assert np.nanmax(np.abs(reading - depth)) < 5 * step  # noise of 0.05 px and 1/8-px rounding only


def test_kinect_on_a_scene_is_deterministic_and_leaves_the_input():
    view = make_scene("desk", size=(48, 64), n_views=1)[0]
    before = view.depth.copy()
    a, _ = kinect_depth(view.depth, view.camera, view.rgb, seed=2)
    b, _ = kinect_depth(view.depth, view.camera, view.rgb, seed=2)
    assert np.array_equal(a, b, equal_nan=True) and np.array_equal(view.depth, before)
    assert 0.01 < np.isnan(a).mean() < 0.5


def test_bad_inputs():
    camera = Camera.from_fov(W, H, 60.0)
    depth = np.full((H, W), 2.0)
    with pytest.raises(TypeError, match="camera"):
        projector_shadow(depth, "cam")
    with pytest.raises(ValueError, match="depth"):
        projector_shadow(np.ones((3, 3)), camera)
    with pytest.raises(ValueError, match="depth_range"):
        kinect_holes(depth, camera, depth_range=(3.0, 1.0))
    with pytest.raises(ValueError, match="unknown options"):
        kinect_depth(depth, camera, focal=3)
    with pytest.raises(ValueError, match="projector_offset"):
        kinect_depth(depth, camera, projector_offset=0.0)
    with pytest.raises(ValueError, match="grazing_deg"):
        grazing_mask(depth, camera, 120.0)
