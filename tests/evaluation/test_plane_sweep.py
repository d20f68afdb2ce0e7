"""Plane-sweep MVS against analytic planes (rendered here by ray-plane intersection) and a scene's exact depth."""
import numpy as np
import pytest

from ddp_lite.core.camera import Camera, look_at
from ddp_lite.world.neighbors import select_neighbors
from ddp_lite.evaluation.plane_sweep import inverse_depth_planes, plane_sweep
from ddp_lite.world.scenes import make_scene

H, W = 48, 64


def _texture(x, y):
    """A smooth, non-repeating grey pattern on world (x, y) metres, in [0, 1]: wavelengths 10–30 cm,
    ≥ 4 px at 1.3 m, so that point-sampling the pixel centres does not alias."""
    value = (np.sin(23.0 * x + 1.0) * np.cos(29.0 * y) + np.sin(41.0 * x - 31.0 * y + 0.3)
             + 0.7 * np.cos(47.0 * x + 37.0 * y))
    return 0.5 + value / 6.0


def _render_plane(camera: Camera, normal, offset):
    """(rgb, depth) of the world plane n·X = offset seen by ``camera``, textured by ``_texture`` of (X, Y)."""
    v, u = np.mgrid[0:camera.height, 0:camera.width].astype(np.float64)
    rays_cam = np.stack([u, v, np.ones_like(u)], -1) @ np.linalg.inv(camera.K).T  # (H, W, 3), z = 1
    pose = camera.world_from_cam
    rays = rays_cam @ pose[:3, :3].T  # world directions (camera z = 1 → depth along the axis)
    centre = pose[:3, 3]
    t = (offset - normal @ centre) / (rays @ normal)  # the depth along the optical axis
    points = centre + t[..., None] * rays
    grey = _texture(points[..., 0], points[..., 1]).astype(np.float32)
    return np.repeat(grey[..., None], 3, -1), t.astype(np.float32)


def _rig(n_neighbors=4):
    cams = [Camera.from_fov(W, H, 60.0)]
    for dx, dy in ((0.2, 0.0), (-0.2, 0.0), (0.0, 0.15), (0.0, -0.15))[:n_neighbors]:
        cams.append(Camera.from_fov(W, H, 60.0, look_at((dx, dy, 0.0), (dx, dy, 1.0))))
    return cams


def _spacing_error(sweep, truth):
    """|1/z − 1/z_true| in units of the planes' inverse-depth spacing, (H, W)."""
    step = abs(1.0 / sweep.planes[1] - 1.0 / sweep.planes[0])
    return np.abs(1.0 / sweep.depth - 1.0 / truth) / step


def _interior(margin=4):
    inner = np.zeros((H, W), bool)
    inner[margin:-margin, margin:-margin] = True
    return inner


def test_planes_uniform_in_inverse_depth():
    planes = inverse_depth_planes(0.5, 5.0, 10)
    assert planes[0] == pytest.approx(0.5) and planes[-1] == pytest.approx(5.0)
    np.testing.assert_allclose(np.diff(1.0 / planes), (1 / 5.0 - 1 / 0.5) / 9)


@pytest.mark.parametrize("tilt_deg", [0.0, 35.0])
def test_plane_recovered_to_the_plane_spacing(tilt_deg):
    """A fronto-parallel and a tilted textured plane: the depth within one plane spacing everywhere
    inside, and the sub-plane refinement well below it (the true depth lies between planes)."""
    tilt = np.radians(tilt_deg)
    normal = np.array([np.sin(tilt), 0.0, np.cos(tilt)])
    cams = _rig()
    views = [_render_plane(c, normal, 1.3) for c in cams]
    truth = views[0][1]
    sweep = plane_sweep((views[0][0], cams[0]), [(rgb, c) for (rgb, _), c in zip(views[1:], cams[1:])],
                        0.8, 3.0, n_planes=24, window=5)
    error = _spacing_error(sweep, truth)[_interior()]
    assert np.all(error <= 1.0), f"worst error {error.max():.2f} plane spacings"
    assert np.median(error) < 0.2, f"median {np.median(error):.3f} spacings: the refinement does not work"
    assert np.median(sweep.probability[_interior()]) > 0.5  # a textured plane is a confident match


def test_untextured_plane_has_low_probability():
    """A flat grey wall matches every plane equally: its probability is near 4/D, below the paper's 0.1."""
    cams = _rig(2)
    flat = np.full((H, W, 3), 0.5, np.float32)
    sweep = plane_sweep((flat, cams[0]), [(flat, c) for c in cams[1:]], 0.8, 3.0, n_planes=64)
    assert sweep.probability.max() < 0.1
    assert sweep.probability.mean() == pytest.approx(4 / 64, abs=0.01)


def test_against_a_scenes_exact_depth():
    """On a rendered scene, the confident pixels are accurate and more accurate than the rest."""
    scene = make_scene("desk", size=(H, W), n_views=4)
    neighbors = [scene[i] for i in select_neighbors(scene, 0, 3)]
    sweep = plane_sweep(scene[0], neighbors, scene.meta["d_min"], scene.meta["d_max"], n_planes=64)
    relative = np.abs(sweep.depth - scene[0].depth) / scene[0].depth
    confident = sweep.probability >= 0.3
    assert 0.3 < confident.mean() < 0.95
    assert np.median(relative[confident]) < 0.03
    assert np.mean(relative[confident] > 0.05) < np.mean(relative[~confident] > 0.05)
    holes = sweep.holes(0.3)
    assert np.array_equal(np.isnan(holes), ~confident)


def test_deterministic_and_inputs_untouched():
    scene = make_scene("house", size=(H, W), n_views=3)
    before = scene[0].rgb.copy()
    a = plane_sweep(scene[0], [scene[1], scene[2]], 2.0, 30.0, n_planes=16)
    b = plane_sweep(scene[0], [scene[1], scene[2]], 2.0, 30.0, n_planes=16)
    assert np.array_equal(a.depth, b.depth) and np.array_equal(a.probability, b.probability)
    assert np.array_equal(scene[0].rgb, before)


def test_bad_inputs():
    scene = make_scene("house", size=(H, W), n_views=2)
    with pytest.raises(ValueError, match="neighbors"):
        plane_sweep(scene[0], [], 1.0, 2.0)
    with pytest.raises(TypeError, match="neighbors"):
        plane_sweep(scene[0], scene[1], 1.0, 2.0)
    with pytest.raises(ValueError, match="d_max"):
        plane_sweep(scene[0], [scene[1]], 2.0, 1.0)
    with pytest.raises(ValueError, match="n_planes"):
        plane_sweep(scene[0], [scene[1]], 1.0, 2.0, n_planes=2)
    with pytest.raises(ValueError, match="window"):
        plane_sweep(scene[0], [scene[1]], 1.0, 2.0, window=4)
    with pytest.raises(ValueError, match="temperature"):
        plane_sweep(scene[0], [scene[1]], 1.0, 2.0, temperature=0.0)
    with pytest.raises(ValueError, match="threshold"):
        plane_sweep(scene[0], [scene[1]], 1.0, 2.0, n_planes=4).holes(1.5)
